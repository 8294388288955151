// expansion_points SCENE FILE.json: where krs::expand puts every kernel instance of an example
// scene that is a sequence, as JSON, for scripts/check_blender.py to compare with the objects
// Blender's glTF importer placed from `krs_export --instances` (the brute-force expansion, not the
// glTF writer, is the reference):
//     {"kernels": [{"level": L, "points": [[x, y, z], ...]}, ...],
//      "instances": [{"kernel": k, "rotation": [9 numbers, row-major], "translation": [x, y, z]},
//      ...]}
// A kernel's points, in its own space: its box's centre (the origin for an unbounded kernel, a
// plane) and that point moved by one along x, y and z (four points pin a rigid motion). An
// instance is its isometry, kernel space to the world (y-up, the scene's frame); the instances of
// a kernel of level L are the isometries of level L, which also place krs_export's "levels below
// L" part. Exit 0 when written, 1 when the file cannot be written, 2 on a bad command line or a
// scene that is no sequence.

#include "krs/expansion.hpp"
#include "krs/io/write_then_rename.hpp"
#include "krs/scenes/example_scenes.hpp"

#include <cstdio>
#include <exception>
#include <string>
#include <variant>
#include <vector>

namespace {

std::string point_text(const krs::vec3d& p)
{
    char text[96];
    std::snprintf(text, sizeof text, "[%.17g, %.17g, %.17g]", p.x, p.y, p.z);
    return text;
}

std::string points_text(const std::vector<krs::vec3d>& points)
{
    std::string out = "[";
    for (std::size_t i = 0; i < points.size(); ++i)
        out += (i ? ", " : "") + point_text(points[i]);
    return out + "]";
}

} // namespace

int main(int argc, char** argv)
{
    if (argc != 3) {
        std::fprintf(stderr, "usage: expansion_points SCENE FILE.json\n");
        return 2;
    }
    const std::string scene = argv[1], path = argv[2];
    int status = 2;
    const bool found = krs::scenes::with_scene(scene, std::nullopt, [&](const auto& s) {
        if constexpr (requires { krs::expand(s.field); }) {
            const auto e = krs::expand(s.field);
            std::string json = "{\"kernels\": [";
            for (std::size_t k = 0; k < s.field.kernels().size(); ++k) {
                const krs::bounding_box b = std::visit(
                    [](const auto& kernel) { return kernel.bound_box(); }, s.field.kernels()[k]);
                const krs::vec3d c = b.is_bounded() ? (krs::vec3d(b.lo) + krs::vec3d(b.hi)) * 0.5
                                                    : krs::vec3d{0, 0, 0};
                json += std::string(k ? ",\n  " : "\n  ") +
                        "{\"level\": " + std::to_string(s.field.kernel_level(k)) +
                        ", \"points\": " +
                        points_text({c, c + krs::vec3d{1, 0, 0}, c + krs::vec3d{0, 1, 0},
                                     c + krs::vec3d{0, 0, 1}}) +
                        "}";
            }
            json += "],\n\"instances\": [";
            for (std::size_t i = 0; i < e.instances.size(); ++i) {
                const auto& in = e.instances[i];
                char rotation[256];
                const auto& a = in.to_world.a;
                std::snprintf(rotation, sizeof rotation,
                              "[%.17g, %.17g, %.17g, %.17g, %.17g, %.17g, %.17g, %.17g, %.17g]",
                              a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8]);
                json += std::string(i ? ",\n  " : "\n  ") +
                        "{\"kernel\": " + std::to_string(in.kernel) +
                        ", \"rotation\": " + rotation +
                        ", \"translation\": " + point_text(in.to_world.t) + "}";
            }
            json += "]}\n";
            try {
                krs::write_file("expansion_points", path, json);
            } catch (const std::exception& failure) {
                std::fprintf(stderr, "%s\n", failure.what());
                status = 1;
                return;
            }
            std::printf("expansion_points: %s: %zu kernels, %zu instances -> %s\n", scene.c_str(),
                        s.field.kernels().size(), e.instances.size(), path.c_str());
            status = 0;
        } else {
            std::fprintf(
                stderr,
                "expansion_points: scene '%s' is not a sequence (krs::expand takes sequences)\n",
                scene.c_str());
        }
    });
    if (!found)
        std::fprintf(stderr, "expansion_points: no scene named '%s'\n", scene.c_str());
    return status;
}
