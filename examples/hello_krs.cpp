#include <krs/krs.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string_view>

int main(int argc, char** argv) {
    if (argc > 1) {                          // no options: -h and --help say so, others are refused
        const bool help = std::string_view(argv[1]) == "-h" || std::string_view(argv[1]) == "--help";
        std::fprintf(help ? stdout : stderr, "usage: hello_krs (no options): a bush of 512 KRS instances drawn as text\n");
        return help ? 0 : 2;
    }
    using scene = krs::sequence<krs::sphere, krs::torus_capsule>;
    scene::builder b;
    b.kernel(krs::sphere({0.3f, 1.1f, 0}, 0.25f));                                // K0: a leaf ball
    b.kernel(krs::torus_capsule({0, 0, 0}, {0.3f, 1.1f, 0}, {0.05f, 0.6f, 0}, 0.05f)); // K0: its bent stem
    for (int i = 0; i < 8; ++i)                                     // R0..R7: 2^8 copies of K0
        b.mirror(krs::mirror({std::cos(2.4f * i), 0, std::sin(2.4f * i)}, 0.4f + 0.3f * i));
    const scene bush = b.build();

    const krs::pinhole_camera camera({0, 4, -10}, {0, 0.5f, 0}, {0, 1, 0}, 40, 72, 28);
    krs::trace_options options;
    options.pixel_footprint = camera.pixel_footprint();
    for (int y = 0; y < camera.height(); ++y, std::putchar('\n'))
        for (int x = 0; x < camera.width(); ++x) {
            const krs::hit<float> h = krs::sphere_trace(bush, camera.primary_ray(x + 0.5f, y + 0.5f), options);
            std::putchar(h.found ? "@%#*+=-:."[std::clamp(int(h.t) - 7, 0, 8)] : ' ');
        }
    std::printf("%.0f kernel instances; distance from the origin: %f\n", bush.instance_count(),
                bush.distance(krs::vec3f{0, 0, 0}));
}
