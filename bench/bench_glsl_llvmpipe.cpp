// bench_glsl_llvmpipe: the GLSL sequence walk's per-level early exit on Mesa's llvmpipe (the CPU's
// OpenGL), timed against the full walk the emitter writes with options.level_early_exit = false.
// The two give the same distance at every point (tests/test_glsl_shading.cpp checks it bit for
// bit); the exit saves the levels below where a point is farther from L_i's bounding sphere than
// the nearest kernel found so far, so it pays far from the finer levels, where the hardware skips
// code that no lane of a wave runs.
//
// Why llvmpipe may not: it runs a group of invocations as SIMD lanes, and in Mesa's gallivm
// (src/gallium/auxiliary/gallivm/lp_bld_nir_soa.c, read in Mesa 21.3.8's copy, not in the 22.3
// this machine runs) if_cond pushes the condition onto the execution mask
// (lp_exec_mask_cond_push) and emits no branch, so code under an `if` (a return, once lowered, is
// nested ifs) would run for every lane, masked. That the skipped levels still run here is a
// hypothesis that fits the figures, not a measurement: on this machine (2 cores, Mesa 22.3)
// full/exit was 0.82-0.89 in two runs of --repeat 9, the tiles no better than the scattered
// points. So the table shows what the exit costs on llvmpipe, not what it saves on a GPU.
//
//     bench_glsl_llvmpipe [--csv FILE] [--repeat R] [--points N]
//
// The CSV goes next to the executable, as <executable>.csv, unless --csv names one. For each
// example scene with level bounds (tree, forest) and three samplings (the tests' box around the
// scene; that box doubled, where more points are far; and the doubled box in tiles of 64 nearby
// points, as a sphere tracer's neighbouring pixels, so lanes that run together leave the walk
// together), N points (default 2^18, at least 64) are evaluated by the scene's distance in one
// compute dispatch; time is the best of R (default 5, at least 1) dispatches, each waited for by
// reading a result back, after one warm-up dispatch (llvmpipe compiles the shader to machine code
// at the first). Built with the benchmarks when the GLSL tests are on (KRS_GLSL_TESTS: Mesa, EGL).

#include "krs/glsl/emitter.hpp"
#include "krs/scenes/example_scenes.hpp"
#include "krs/scenes/scene_files.hpp"
#include "support/gl_program.hpp" // tests/support: the GLSL tests' context, compile and link
#include "support/text.hpp"
#include "support/timing.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using krs::vec3f;

struct timing {
    double seconds;
    std::vector<float> distances;
};

// The scene's distance at every point, in one dispatch; best of `repeat` after a warm-up.
template <class S>
timing time_distance(const S& field, bool early_exit, const std::vector<float>& points, int repeat)
{
    krs::glsl::options o{krs::glsl::target::glsl450, krs::glsl::data_mode::constants, "data", 0};
    o.level_early_exit = early_exit;
    krs::glsl::emitter e(o);
    const std::string fn = e.add(field, "scene");
    const std::string text = "#version 430 core\nlayout(local_size_x = 64) in;\n" + e.source() +
                             "layout(std430, binding = 1) readonly buffer bench_in { float points[]; };\n"
                             "layout(std430, binding = 2) writeonly buffer bench_out { float results[]; };\n"
                             "uniform uint count;\n"
                             "void main() {\n    uint i = gl_GlobalInvocationID.x;\n"
                             "    if (i >= count) return;\n"
                             "    results[i] = " + fn + "(vec3(points[3u * i], points[3u * i + 1u], points[3u * i + 2u]));\n}\n";
    const GLuint program = krs_test::link({krs_test::compile(GL_COMPUTE_SHADER, text)});
    const std::size_t count = points.size() / 3;
    GLuint buffers[2];
    glGenBuffers(2, buffers);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, buffers[0]);
    glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(points.size() * sizeof(float)), points.data(), GL_STATIC_DRAW);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, buffers[1]);
    glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(count * sizeof(float)), nullptr, GL_DYNAMIC_READ);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, buffers[0]);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, buffers[1]);
    glUseProgram(program);
    glUniform1ui(glGetUniformLocation(program, "count"), GLuint(count));
    // Each timed dispatch ends by reading a result back, after a barrier: the read cannot
    // complete before the dispatch has (glFinish alone is not a promise that llvmpipe ran it).
    const auto dispatch = [&] {
        glDispatchCompute(GLuint((count + 63) / 64), 1, 1);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        float last = 0;
        glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, GLintptr((count - 1) * sizeof(float)), sizeof last, &last);
        glFinish();
    };
    dispatch(); // warm-up: llvmpipe's JIT
    timing t;
    t.seconds = bench::best_seconds(repeat, dispatch);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    t.distances.resize(count);
    glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(count * sizeof(float)), t.distances.data());
    glDeleteBuffers(2, buffers);
    glDeleteProgram(program);
    if (glGetError() != GL_NO_ERROR) throw std::runtime_error("OpenGL error");
    return t;
}

} // namespace

int main(int argc, char** argv)
{
    std::string csv_path = bench::csv_next_to_executable(argv[0]);
    int repeat = 5;
    std::size_t count = std::size_t(1) << 18;
    const auto usage = [&] {
        std::fprintf(stderr,
                     "usage: %s [--csv FILE] [--repeat R] [--points N]   (whole numbers: R in [1, 1000], N in "
                     "[64, 2^26])\n",
                     argv[0]);
        return 2;
    };
    // A whole number in [least, most], or nothing.
    const auto whole = [](const char* text, long least, long most) -> std::optional<long> {
        char* end = nullptr;
        errno = 0;
        const long v = std::strtol(text, &end, 10);
        if (end == text || *end != '\0' || errno != 0 || v < least || v > most) return std::nullopt;
        return v;
    };
    for (int i = 1; i < argc; i += 2) {
        const std::string a = argv[i];
        if (i + 1 >= argc) return usage(); // an option without its value
        if (a == "--csv") {
            csv_path = argv[i + 1];
        } else if (a == "--repeat") {
            const auto v = whole(argv[i + 1], 1, 1000);
            if (!v) return usage();
            repeat = int(*v);
        } else if (a == "--points") {
            const auto v = whole(argv[i + 1], 64, long(1) << 26);
            if (!v) return usage();
            count = std::size_t(*v);
        } else {
            return usage();
        }
    }
    krs_test::require_context();
    std::ofstream csv(csv_path);
    csv << "scene,region,points,early_exit_ms,full_walk_ms,full_over_early,equal_distances\n";
    std::printf("GLSL sequence distance on llvmpipe: per-level early exit against the full walk (%zu points, best of "
                "%d)\n\n",
                count, repeat);
    std::printf("%-7s %-10s %12s %12s %9s %9s\n", "scene", "region", "exit (ms)", "full (ms)", "full/exit", "equal");
    const auto row = [&](const auto& scene) {
        for (const float scale : {1.0f, 2.0f, -2.0f}) {
            // scale < 0: the box doubled, in clusters of 64 consecutive points (one work group)
            // within 1/100 of the box around a random center, as the pixels of a tile are: lanes
            // that run together then mostly leave the walk together.
            const bool clustered = scale < 0;
            const float s = std::abs(scale);
            std::mt19937_64 g(0xbe7c);
            std::uniform_real_distribution<float> u(-1.0f, 1.0f);
            std::vector<float> points(3 * count);
            vec3f center = scene.sample_center;
            for (std::size_t i = 0; i < count; ++i) {
                float spread = s;
                if (clustered) {
                    if (i % 64 == 0)
                        center = scene.sample_center + vec3f{s * scene.sample_half.x * u(g), s * scene.sample_half.y * u(g),
                                                             s * scene.sample_half.z * u(g)};
                    spread = 0.01f * s;
                }
                points[3 * i] = center.x + spread * scene.sample_half.x * u(g);
                points[3 * i + 1] = center.y + spread * scene.sample_half.y * u(g);
                points[3 * i + 2] = center.z + spread * scene.sample_half.z * u(g);
            }
            const timing early = time_distance(scene.field, true, points, repeat);
            const timing full = time_distance(scene.field, false, points, repeat);
            std::size_t equal = 0;
            for (std::size_t i = 0; i < count; ++i) equal += early.distances[i] == full.distances[i];
            const std::string region = clustered ? "x2 tiles" : (scale == 1.0f ? "box" : "box x2");
            const double ratio = full.seconds / early.seconds;
            std::printf("%-7s %-10s %12.2f %12.2f %9.2f %4zu/%zu\n", scene.name.c_str(), region.c_str(),
                        1e3 * early.seconds, 1e3 * full.seconds, ratio, equal, count);
            csv << bench::format("%s,%s,%zu,%.4f,%.4f,%.4f,%zu\n", scene.name.c_str(), region.c_str(), count,
                                 1e3 * early.seconds, 1e3 * full.seconds, ratio, equal);
        }
    };
    row(krs::scenes::tree_scene::build());
    row(krs::scenes::forest_scene::build());
    std::printf("\nCSV: %s\n", csv_path.c_str());
    return 0;
}
