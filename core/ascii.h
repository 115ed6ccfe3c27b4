// ASCII case folding for protocol and file-format tokens (HTTP header values,
// URL schemes and hosts, file extensions, STEP/IGES unit names): independent
// of the locale, as those grammars are.
#pragma once

#include <string>
#include <string_view>

namespace nurbsrt {

inline std::string ascii_lower(std::string_view s) {
    std::string out(s);
    for (char& c : out)
        if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    return out;
}

}  // namespace nurbsrt
