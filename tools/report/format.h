#pragma once
/// printf-style formatting into a std::string (the report's tables and notes).
#include <string>

namespace mudcrack::report {

/// The printf formatting of the arguments, any length.
std::string format(const char* fmt, ...) __attribute__((format(printf, 1, 2)));

}  // namespace mudcrack::report
