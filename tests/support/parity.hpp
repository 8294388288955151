#pragma once
// Comparing two evaluations that the library promises equal: a packet lane against the scalar path,
// a lockstep walk against separate walks, a located kernel against the field.
//
// krs_tests and krs_tests_native compile with -ffp-contract=off, and there they are bit-identical.
// krs_parity_contract_native (tests/CMakeLists.txt) compiles the parity tests the way a user does:
// g++'s default -ffp-contract=fast with -march=native, so FMA is available and g++ fuses a*b+c in
// each path as it sees fit (KRS_TEST_FP_CONTRACT is defined there). The two paths then round
// differently, and the gap allowed is `contraction_tolerance` of the scene's extent (the one stated
// in krs/field.hpp and docs/stability.md, "Packet and scalar results under FMA contraction").
// Without FMA (the default x86-64 target) -ffp-contract changes nothing: g++ 12.2 writes the same
// object file for test_packet.cpp with -ffp-contract=off and =fast.
//
// Each comparison counts bit-identical pairs and the worst gap, and the contraction build prints them.

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace krs_test {

#if defined(KRS_TEST_FP_CONTRACT)
inline constexpr bool contraction = true;
#else
inline constexpr bool contraction = false;
#endif

// The gap allowed under contraction, relative to the extent of the scene (see above).
inline constexpr double contraction_tolerance = 1e-6;

struct parity {
    std::string name;
    double extent = 1; // the scene's size: gaps are measured against it
    long compared = 0, identical = 0;
    double worst = 0; // largest |a - b| / extent

    // Whether a and b agree as this build promises: bit for bit, or within the tolerance.
    bool agree(double a, double b)
    {
        ++compared;
        if (a == b || (std::isnan(a) && std::isnan(b))) {
            ++identical;
            return true;
        }
        const double gap = std::abs(a - b) / extent;
        worst = std::max(worst, std::isnan(gap) ? INFINITY : gap);
        return contraction && gap <= contraction_tolerance;
    }

    // Prints the counts in the contraction build (call once the comparisons are done).
    void report() const
    {
        if (contraction && compared > 0)
            MESSAGE("parity " << name << ": " << identical << " of " << compared << " bit-identical ("
                              << 100.0 * double(identical) / double(compared) << "%), worst gap " << worst
                              << " of the extent");
    }
};

} // namespace krs_test
