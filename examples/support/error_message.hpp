#pragma once
// What a program prints for an exception it stops on: "<program>: <message>", one prefix. The
// library's krs::invalid_parameter reads "krs: <parameter>: ..." (krs/core/validate.hpp); printed
// after the program's own name that gave "krs_export: krs: ...", two prefixes where the reader
// wants one, so its message() (without "krs: ") is printed instead.

#include "krs/core/validate.hpp"

#include <exception>
#include <string>

namespace example {

inline std::string message_of(const std::exception& e)
{
    if (const auto* p = dynamic_cast<const krs::invalid_parameter*>(&e)) return p->message();
    return e.what();
}

} // namespace example
