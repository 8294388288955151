#pragma once
// printf-style formatting into a std::string, for the benchmarks' tables.

#include <cstdarg>
#include <cstdio>
#include <string>

namespace bench {

std::string format(const char* f, ...) __attribute__((format(printf, 1, 2)));
inline std::string format(const char* f, ...)
{
    char buffer[512];
    va_list args;
    va_start(args, f);
    std::vsnprintf(buffer, sizeof buffer, f, args);
    va_end(args);
    return buffer;
}

} // namespace bench
