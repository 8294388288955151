#pragma once
// printf-style formatting into a std::string, for the benchmarks' tables, and where their CSV goes.

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

// A benchmark's default CSV: <executable>.csv next to the binary, from wherever it is run, so
// scripts/benchmark_report.py finds every CSV in the build's bench/ directory (three benchmarks
// wrote theirs to the working directory, and a report run from elsewhere lost their sections).
inline std::string csv_next_to_executable(const char* argv0)
{
    const std::string self = argv0;
    return (self.find('/') == std::string::npos ? "./" + self : self) + ".csv";
}

} // namespace bench
