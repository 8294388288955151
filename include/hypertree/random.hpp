#pragma once
// The generator's pseudo-random numbers: deterministic for a seed, and splittable so that any
// number of threads produce the same tree (paper section 6 with the chunks of hypertree/generate).
//
// `random_stream` is splitmix64 (Steele, Lea and Flood 2014): a Weyl sequence with step
// 0x9e3779b97f4a7c15 (odd, so the state visits all 2^64 values) passed through a 64-bit mixer.
// It is tiny, fast and good enough for the chaos game; `derive(seed, stream)` mixes a seed with a
// stream number so that chunks and the parameter draw use independent, reproducible streams.

#include <cstdint>

namespace hypertree {

class random_stream {
public:
    explicit random_stream(std::uint64_t seed) : state_(seed) {}

    std::uint64_t next()
    {
        state_ += 0x9e3779b97f4a7c15ull;
        return mix(state_);
    }
    // The whole state: random_stream(state()) continues this stream.
    std::uint64_t state() const { return state_; }
    // Uniform in [0, 1): the top 53 bits, so every value is exact in double.
    double uniform() { return double(next() >> 11) * 0x1.0p-53; }
    // Uniform in [-1, 1).
    double symmetric() { return 2.0 * uniform() - 1.0; }

    static std::uint64_t mix(std::uint64_t z)
    {
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
    // An independent stream for (seed, stream): mixing twice keeps nearby seeds and stream numbers
    // from giving correlated sequences.
    static random_stream derive(std::uint64_t seed, std::uint64_t stream)
    {
        return random_stream(mix(mix(seed) ^ (stream * 0xd1b54a32d192ed03ull + 0x632be59bd9b4e019ull)));
    }

private:
    std::uint64_t state_;
};

} // namespace hypertree
