// bench_glsl_llvmpipe: the GLSL sequence walk's per-level early exit on Mesa's llvmpipe (the CPU's
// OpenGL), timed against the full walk the emitter writes with options.level_early_exit = false.
// The two give the same distance at every point (tests/test_glsl_shading.cpp checks it bit for
// bit); the exit saves the levels below where a point is farther from L_i's bounding sphere than
// the nearest kernel found so far, so it pays far from the finer levels: where the hardware skips
// code that no lane of a wave runs. llvmpipe does not: it runs each shader invocation group as
// SIMD lanes and compiles an `if` (a return, once lowered, is nested ifs) to a lane mask pushed
// over code that runs regardless (gallivm's if_cond; only loops test for a mask of no lanes and
// branch). There the skipped levels still run and the exit's tests are extra work, so this table
// shows what the exit costs on llvmpipe, not what it saves on a GPU: on this machine (2 cores,
// Mesa 22.3) full/exit was 0.82-0.89 in two runs of --repeat 9, the tiles no better than the
// scattered points, as masks without branches predict.
//
//     bench_glsl_llvmpipe [--csv FILE] [--repeat R] [--points N]
//     (the CSV goes next to the executable, as <executable>.csv, unless --csv names one)
//
// For each example scene with level bounds (tree, forest) and three samplings (the tests' box
// around the scene; that box doubled, where more points are far; and the doubled box in tiles of
// 64 nearby points, as a sphere tracer's neighbouring pixels, so lanes that run together leave the
// walk together), N points (default
// 2^18) are evaluated by the scene's distance in one compute dispatch; time is the best of R
// (default 5) dispatches, each waited for by reading a result back, after one warm-up dispatch (llvmpipe
// compiles the shader to machine code at the first). Built with the benchmarks when the GLSL
// tests are on (KRS_GLSL_TESTS: Mesa, EGL).

#define GL_GLEXT_PROTOTYPES 1
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/glcorearb.h>

#include "krs/glsl/emitter.hpp"
#include "krs/glsl/example_scenes.hpp"
#include "support/text.hpp"
#include "support/timing.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using krs::vec3f;

// One headless llvmpipe context (surfaceless EGL, OpenGL 4.3 core), as the GLSL tests make it.
void make_context()
{
    const EGLDisplay display = eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    EGLint major = 0, minor = 0;
    if (display == EGL_NO_DISPLAY || !eglInitialize(display, &major, &minor))
        throw std::runtime_error("no EGL display (is libgl1-mesa-dri installed?)");
    eglBindAPI(EGL_OPENGL_API);
    const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 3,
                                 EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    const EGLContext context = eglCreateContext(display, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attributes);
    if (context == EGL_NO_CONTEXT || !eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context))
        throw std::runtime_error("no OpenGL 4.3 core context");
}

GLuint compute_program(const std::string& text)
{
    const GLuint shader = glCreateShader(GL_COMPUTE_SHADER);
    const char* source = text.c_str();
    glShaderSource(shader, 1, &source, nullptr);
    glCompileShader(shader);
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[4096] = {};
        glGetShaderInfoLog(shader, sizeof log, nullptr, log);
        throw std::runtime_error(std::string("shader compilation failed: ") + log);
    }
    const GLuint program = glCreateProgram();
    glAttachShader(program, shader);
    glLinkProgram(program);
    glDeleteShader(shader);
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (!ok) throw std::runtime_error("program link failed");
    return program;
}

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
    const GLuint program = compute_program("#version 430 core\nlayout(local_size_x = 64) in;\n" + e.source() +
                                           "layout(std430, binding = 1) readonly buffer bench_in { float points[]; };\n"
                                           "layout(std430, binding = 2) writeonly buffer bench_out { float results[]; };\n"
                                           "uniform uint count;\n"
                                           "void main() {\n    uint i = gl_GlobalInvocationID.x;\n"
                                           "    if (i >= count) return;\n"
                                           "    results[i] = " + fn + "(vec3(points[3u * i], points[3u * i + 1u], points[3u * i + 2u]));\n}\n");
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
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string a = argv[i];
        if (a == "--csv") csv_path = argv[i + 1];
        else if (a == "--repeat") repeat = std::max(1, std::atoi(argv[i + 1]));
        else if (a == "--points") count = std::size_t(std::max(64, std::atoi(argv[i + 1])));
        else {
            std::fprintf(stderr, "usage: %s [--csv FILE] [--repeat R] [--points N]\n", argv[0]);
            return 2;
        }
    }
    make_context();
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
    row(krs::glsl::examples::tree());
    row(krs::glsl::examples::forest());
    std::printf("\nCSV: %s\n", csv_path.c_str());
    return 0;
}
