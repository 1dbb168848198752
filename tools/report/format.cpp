#include "tools/report/format.h"

#include <cstdarg>
#include <cstdio>
#include <vector>

namespace mudcrack::report {

std::string format(const char* fmt, ...) {
    va_list args;
    va_start(args, fmt);
    va_list copy;
    va_copy(copy, args);
    const int n = std::vsnprintf(nullptr, 0, fmt, copy);
    va_end(copy);
    std::vector<char> buf(n > 0 ? n + 1 : 1, '\0');
    if (n > 0) std::vsnprintf(buf.data(), buf.size(), fmt, args);
    va_end(args);
    return std::string(buf.data());
}

}  // namespace mudcrack::report
