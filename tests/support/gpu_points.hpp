#pragma once
// A field's emitted GLSL run at many points on llvmpipe: NAME(p) and NAME_locate(p) in a compute
// shader, one result per point (the GLSL tests compare them with the C++).

#include "krs/core/vec3.hpp"

#include "gl_context.hpp"

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace krs_test {

// What one point gives on the GPU: distance, then locate's point, kernel, level and bits.
struct gpu_result {
    float distance;
    krs::vec3f kernel_point;
    std::uint32_t kernel, level;
    std::uint64_t reflections;
};

// Runs a compute shader over the points: `snippet` (a 330 or 450 snippet without #version), then
// a main that reads the point p and runs `body`, which writes the point's `floats_per_point`
// results to results[N * i + k] (N spelled `krs_n` in the body). Returns them, point by point.
// `data` is bound as the block of buffer mode (UBO `data_name`_block for 330 code when
// `uniform_block`, else SSBO binding 0); empty for constants mode.
inline std::vector<float> run_point_program(const std::string& snippet, const std::string& body, std::size_t floats_per_point,
                                            const std::vector<krs::vec3f>& points, const std::vector<float>& data,
                                            bool uniform_block, const std::string& data_name)
{
    require_context();
    const std::string text = "#version 430 core\nlayout(local_size_x = 64) in;\n" + snippet +
                             "layout(std430, binding = 1) readonly buffer krs_points { float points[]; };\n"
                             "layout(std430, binding = 2) writeonly buffer krs_results { float results[]; };\n"
                             "uniform uint count;\n"
                             "const uint krs_n = " + std::to_string(floats_per_point) + "u;\n"
                             "void main() {\n"
                             "    uint i = gl_GlobalInvocationID.x;\n"
                             "    if (i >= count) return;\n"
                             "    vec3 p = vec3(points[3u * i], points[3u * i + 1u], points[3u * i + 2u]);\n" +
                             body + "}\n";
    const GLuint program = link({compile(GL_COMPUTE_SHADER, text)});
    glUseProgram(program);
    GLuint data_buffer = 0;
    if (!data.empty()) {
        if (uniform_block) {
            data_buffer = buffer(GL_UNIFORM_BUFFER, data.data(), data.size() * sizeof(float), GL_DYNAMIC_DRAW);
            const GLuint index = glGetUniformBlockIndex(program, (data_name + "_block").c_str());
            REQUIRE(index != GL_INVALID_INDEX);
            glUniformBlockBinding(program, index, 0);
            glBindBufferBase(GL_UNIFORM_BUFFER, 0, data_buffer);
        } else {
            data_buffer = buffer(GL_SHADER_STORAGE_BUFFER, data.data(), data.size() * sizeof(float), GL_DYNAMIC_DRAW);
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, data_buffer);
        }
    }
    std::vector<float> packed;
    packed.reserve(points.size() * 3);
    for (const krs::vec3f& p : points) packed.insert(packed.end(), {p.x, p.y, p.z});
    const GLuint in = buffer(GL_SHADER_STORAGE_BUFFER, packed.data(), packed.size() * sizeof(float), GL_STATIC_DRAW);
    const GLuint out = buffer(GL_SHADER_STORAGE_BUFFER, nullptr, points.size() * floats_per_point * sizeof(float), GL_DYNAMIC_READ);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, in);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, out);
    glUniform1ui(glGetUniformLocation(program, "count"), GLuint(points.size()));
    glDispatchCompute(GLuint((points.size() + 63) / 64), 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    std::vector<float> raw(points.size() * floats_per_point);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, out);
    glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(raw.size() * sizeof(float)), raw.data());
    REQUIRE(glGetError() == GL_NO_ERROR);
    const GLuint buffers[3] = {in, out, data_buffer};
    glDeleteBuffers(data_buffer ? 3 : 2, buffers);
    glDeleteProgram(program);
    return raw;
}

// Runs NAME(p) and NAME_locate(p) of `snippet` over the points (see run_point_program).
inline std::vector<gpu_result> run_points(const std::string& snippet, const std::string& name, const std::vector<krs::vec3f>& points,
                                          const std::vector<float>& data, bool uniform_block, const std::string& data_name)
{
    const std::string body = "    krs_location w = " + name + "_locate(p);\n"
                             "    results[krs_n * i] = " + name + "(p);\n"
                             "    results[krs_n * i + 1u] = w.kernel_point.x;\n"
                             "    results[krs_n * i + 2u] = w.kernel_point.y;\n"
                             "    results[krs_n * i + 3u] = w.kernel_point.z;\n"
                             "    results[krs_n * i + 4u] = uintBitsToFloat(w.kernel);\n"
                             "    results[krs_n * i + 5u] = uintBitsToFloat(w.level);\n"
                             "    results[krs_n * i + 6u] = uintBitsToFloat(w.reflections.x);\n"
                             "    results[krs_n * i + 7u] = uintBitsToFloat(w.reflections.y);\n";
    const std::vector<float> raw = run_point_program(snippet, body, 8, points, data, uniform_block, data_name);
    std::vector<gpu_result> results(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
        const float* r = &raw[8 * i];
        std::uint32_t bits[4];
        std::memcpy(bits, r + 4, sizeof bits);
        results[i] = {r[0], {r[1], r[2], r[3]}, bits[0], bits[1], bits[2] | (std::uint64_t(bits[3]) << 32)};
    }
    return results;
}

} // namespace krs_test
