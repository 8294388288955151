#pragma once
// The check behind every "bad input is refused by name" test (the rule of
// include/krs/core/validate.hpp: a clear krs::invalid_parameter naming the parameter): a call that
// must throw krs::invalid_parameter whose parameter() is exactly the name given, e.g.
// "slice_plane.origin" (rejects), or whose message contains the name given (rejects_naming).
// Written once here, so that such tests differ only in what they spoil.
//
// It fails the test case both when the call throws with another name and when it throws nothing
// (or returns normally); any other exception propagates to doctest, which fails the case too.

#include "krs/core/validate.hpp"

#include <doctest/doctest.h>

#include <string>

namespace krs_test {

template <class F>
void rejects(F&& call, const std::string& parameter)
{
    try {
        call();
    } catch (const krs::invalid_parameter& e) {
        CHECK(e.parameter() == parameter);
        return;
    }
    FAIL("no krs::invalid_parameter for " << parameter);
}

// The same check by the message: the call must throw krs::invalid_parameter whose what() contains
// `name` (the hypertree's checks, whose tests name a parameter by a path the message holds).
template <class F>
void rejects_naming(F&& call, const std::string& name)
{
    try {
        call();
    } catch (const krs::invalid_parameter& e) {
        CHECK_MESSAGE(std::string(e.what()).find(name) != std::string::npos, e.what());
        return;
    }
    FAIL("no krs::invalid_parameter naming " << name);
}

} // namespace krs_test
