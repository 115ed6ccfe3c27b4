#include "server/redact.h"

namespace nurbsrt::server {

std::string without_prefixes(std::string message, std::initializer_list<std::string> prefixes) {
    for (const std::string& p : prefixes)
        if (!p.empty())
            for (size_t at; (at = message.find(p)) != std::string::npos;) message.erase(at, p.size());
    return message;
}

}  // namespace nurbsrt::server
