#include "server/common/redact.h"

namespace nurbsrt::server {

std::string without_prefixes(std::string message, std::initializer_list<std::string> prefixes) {
    for (const std::string& p : prefixes)
        if (!p.empty())
            for (size_t at; (at = message.find(p)) != std::string::npos;) message.erase(at, p.size());
    return message;
}

std::string with_scratch_files_named(std::string message, const std::string& dir) {
    if (dir.empty()) return message;
    const std::string prefix = dir + "/";
    auto name_char = [](char c) {
        return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' ||
               c == '-';
    };
    for (size_t at; (at = message.find(prefix)) != std::string::npos;) {
        size_t end = at + prefix.size();
        while (end < message.size() && name_char(message[end])) ++end;
        const std::string name = message.substr(at + prefix.size(), end - at - prefix.size());
        const char* what = name.rfind("upload-", 0) == 0      ? "the upload"
                           : name.rfind("converted-", 0) == 0 ? "the converted file"
                                                              : "a scratch file";
        message.replace(at, end - at, what);
    }
    return message;
}

}  // namespace nurbsrt::server
