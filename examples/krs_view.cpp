// krs_view: a window onto the emitted GLSL. It runs a whole Shadertoy program on the GPU, in real
// time: the program of an example scene (--scene NAME, as glsl_export writes it,
// krs/scenes/example_scenes.hpp; --list-scenes prints them, --seed S builds a seeded one at S) or
// a user's own file (--glsl FILE, any Shadertoy Image tab).
//
//   krs_view [--scene NAME | --glsl FILE] [--width W --height H] [--time T] [--output FILE.png]
//   krs_view ... --frames N [--output FILE.png] [--accumulate]      (headless)
//   krs_view --glsl FILE --frames N --output FILE.png --exit-after-reload SECONDS
//
// (--screenshot FILE.png, the older spelling of --output, is still taken.)
//
// The inputs are Shadertoy's (support/shadertoy_host.hpp): iTime orbits the scene's camera, a drag
// turns it (iMouse, the program's own krs::pinhole_camera turn); space pauses time, P writes the
// frame as PNG, Esc quits. While time is paused and the pointer still, every frame adds a jittered
// sample and the window shows their mean (support/progressive_frame.hpp). The title shows the
// frame's size, the milliseconds its drawing took (measured to the GPU's end of it by glFinish, so
// it is the program's time, not the screen's refresh) and the samples.
//
// A --glsl file is watched (support/file_watch.hpp): when it changes on disk it is compiled again;
// a program that does not compile leaves the last good one running, with the compiler's log on
// stderr and its first line in the title.
//
// Headless (--frames N): the window stays hidden, N frames are drawn at --time T (default 0, time
// does not run: the frames are reproducible), the last is written to --output, and the time per
// frame is printed. Without --accumulate every frame is the plain one (fragCoord at the pixel
// centers), which is the frame `glsl_export --reference` computes on the CPU. With
// --exit-after-reload S, the viewer waits up to S seconds for the --glsl file to change and
// compile, then draws the N frames of the new program (a first program that does not compile is
// then reported and waited out, not fatal): the reload test's deterministic end.
//
// A window needs a display: with none, or no OpenGL 3.3 core context, it prints one line and
// exits 1 (run it under `xvfb-run -a` on a machine without a screen: Mesa's llvmpipe draws there).

#include "krs/scenes/example_scenes.hpp"
#include "krs/scenes/scene_files.hpp"

#include "support/command_line.hpp"
#include "support/common_options.hpp"
#include "support/error_message.hpp"
#include "support/example_io.hpp"
#include "support/file_watch.hpp"
#include "support/output_path.hpp"
#include "support/gl_window.hpp"
#include "support/progressive_frame.hpp"
#include "support/scene_choice.hpp"
#include "support/shadertoy_host.hpp"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>

namespace {

namespace ex = krs::scenes;
using clock_type = std::chrono::steady_clock;

struct options {
    std::string scene = "tree", glsl, screenshot;
    std::optional<std::uint32_t> seed; // --seed: the scene's, else its own
    int width = ex::frame_width, height = ex::frame_height;
    int frames = 0; // 0: interactive
    float time = 0;
    bool accumulate = false;
    float reload_seconds = 0; // --exit-after-reload; 0: not given
    bool headless() const { return frames > 0; }
};

options parse(int argc, char** argv)
{
    options o;
    example::command_line args(
        "krs_view", "A window running a scene's Shadertoy program (or your own) in real time. "
                    "Keys: space pauses time, P writes the frame as PNG, Esc quits; drag to turn.");
    const example::scene_choice scenes(args, o.scene, example::all_scene_names(), "the example scene whose program runs");
    args.text("--glsl", o.glsl,
              "run this Shadertoy program (mainImage) instead, reloaded when it changes", "FILE");
    example::add_image_size(args, o.width, o.height);
    args.number("--time", o.time, 0.0, 1e6, false,
                "iTime at the start, seconds (headless: throughout)");
    args.integer("--frames", o.frames, 1, 1000000,
                 "headless: draw this many frames, print their time and exit");
    example::add_output_file(args, o.screenshot, "FILE.png",
                             "headless: write the last frame to this PNG; interactive: where P writes "
                             "(default krs_view.png)",
                             "--screenshot");
    args.app().add_flag("--accumulate", o.accumulate,
                        "headless: each frame adds a jittered sample to the mean");
    args.number("--exit-after-reload", o.reload_seconds, 0.0, 3600.0, true,
                "headless, with --glsl: wait up to this many seconds for the file to change and "
                "compile, then draw --frames of the new program");
    args.parse(argc, argv);
    o.seed = scenes.seed();
    const auto given = [&](const char* name) { return args.app().count(name) > 0; };
    if (given("--glsl") && (given("--scene") || given("--seed")))
        args.fail("--glsl, --scene, --seed: run one program, a file or a scene");
    if (given("--glsl") && !std::filesystem::is_regular_file(o.glsl))
        args.fail("--glsl: '" + o.glsl + "' is not a file");
    if (given("--accumulate") && !o.headless())
        args.fail("--accumulate: applies to --frames (a window accumulates when still)");
    if (given("--exit-after-reload") && (!o.headless() || o.glsl.empty()))
        args.fail("--exit-after-reload: needs --glsl FILE and --frames N");
    if (o.screenshot.empty() && !o.headless()) o.screenshot = "krs_view.png";
    // The screenshot's path is checked before the window opens, as every program's outputs are
    // (support/output_path.hpp): a PNG name, no directory, a directory that takes a file.
    if (!o.screenshot.empty()) example::require_output_file(args, "--output", o.screenshot, {".png"});
    return o;
}

// The program's text and its name in messages: the scene's, emitted here as glsl_export writes it.
std::string scene_program(const std::string& name, std::optional<std::uint32_t> seed)
{
    std::string text;
    ex::with_scene(name, seed, [&](const auto& s) { text = ex::file_text(s, ex::shadertoy_file); });
    return text;
}

// The first line of a compiler log: what fits in a title.
std::string first_line(const std::string& log)
{
    const std::size_t end = log.find('\n');
    return end == std::string::npos ? log : log.substr(0, end);
}

// What the viewer runs and how it got there: the current good program, and the file behind it.
struct viewer {
    const options& o;
    std::string name;
    std::optional<example::file_watch> watch;
    example::shadertoy_program program;
    std::string error; // the last compile's log, empty when it compiled
    int looks = 0;     // changes of the watched file seen (the first look is one)
    int reloads = 0;   // changes after the first look that compiled

    // Compiles `text`; a good program replaces the running one and restarts iFrame.
    bool load(const std::string& text)
    {
        std::string log;
        example::shadertoy_program next = example::shadertoy_program::build(text, log);
        if (!next) {
            error = log;
            std::fprintf(stderr, "krs_view: cannot compile %s:\n%s\n", name.c_str(), log.c_str());
            return false;
        }
        program = std::move(next);
        error.clear();
        return true;
    }
    // Looks at the watched file; true when a new good program was loaded from it.
    bool poll()
    {
        if (!watch || !watch->changed()) return false;
        const std::optional<std::string> text = watch->read();
        if (!text) return false; // a partial save: the next change reads it whole
        const bool first_look = looks++ == 0;
        const bool loaded = load(*text);
        if (loaded && !first_look) {
            ++reloads;
            std::fprintf(stderr, "krs_view: reloaded %s\n", name.c_str());
        }
        return loaded;
    }
};

bool write_frame(const example::progressive_frame& frame, const std::string& path)
{
    // The framebuffer's bytes as values b / 255, which write_png's round(255 v) gives back exactly.
    const std::vector<unsigned char> bytes = frame.read_rgb();
    std::vector<float> rgb(bytes.size());
    std::transform(bytes.begin(), bytes.end(), rgb.begin(), [](unsigned char b) { return float(b) / 255.0f; });
    if (!example::write_png("krs_view", path, frame.width(), frame.height(), rgb, 1.0f)) return false;
    std::printf("krs_view: wrote the %dx%d frame (%u sample%s) to %s\n", frame.width(),
                frame.height(), frame.samples(), frame.samples() == 1 ? "" : "s", path.c_str());
    return true;
}

double milliseconds_since(clock_type::time_point start)
{
    return std::chrono::duration<double, std::milli>(clock_type::now() - start).count();
}

// Draws one sample of the program into `frame` and waits for the GPU to finish it: the time
// returned is the drawing's.
double draw_sample(const viewer& v, example::progressive_frame& frame, example::shadertoy_inputs in)
{
    const clock_type::time_point start = clock_type::now();
    frame.add_sample([&](std::array<float, 2> jitter) {
        in.jitter = jitter;
        v.program.draw(in);
    });
    glFinish();
    return milliseconds_since(start);
}

int run_headless(viewer& v, example::progressive_frame& frame)
{
    const options& o = v.o;
    frame.resize(o.width, o.height);
    if (o.reload_seconds > 0) {
        // Waits for the file to change and compile; the frames below are then the new program's.
        const clock_type::time_point start = clock_type::now();
        while (v.reloads == 0) {
            if (milliseconds_since(start) > 1000.0 * double(o.reload_seconds)) {
                std::fprintf(
                    stderr,
                    "krs_view: %s did not change into a program that compiles within %g s\n",
                    v.name.c_str(), double(o.reload_seconds));
                return 1;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
            v.poll();
        }
    }
    if (!v.program) return 1; // its log is printed
    example::shadertoy_inputs in;
    in.width = float(o.width), in.height = float(o.height);
    in.time = o.time;
    // The first frame also pays the driver's compile of the program (llvmpipe compiles at the first
    // draw), so it is reported apart from the others.
    double first = 0, rest = 0, fastest = 1e300;
    for (int i = 0; i < o.frames; ++i) {
        if (!o.accumulate) frame.reset();
        in.frame = i;
        const double ms = draw_sample(v, frame, in);
        (i == 0 ? first : rest) += ms;
        if (i > 0) fastest = std::min(fastest, ms);
    }
    std::printf(
        "krs_view: %s: %d frame%s of %dx%d on %s: the first %.2f ms (with the driver's compile)",
        v.name.c_str(), o.frames, o.frames == 1 ? "" : "s", o.width, o.height,
        reinterpret_cast<const char*>(glGetString(GL_RENDERER)), first);
    if (o.frames > 1)
        std::printf(", then %.2f ms per frame (mean; fastest %.2f ms)", rest / (o.frames - 1),
                    fastest);
    std::printf("\n");
    if (!o.screenshot.empty() && !write_frame(frame, o.screenshot)) return 1;
    return 0;
}

// Keys arrive by callback; the loop reads what they asked for.
struct key_requests {
    bool toggle_pause = false, screenshot = false;
};
void on_key(GLFWwindow* window, int key, int, int action, int)
{
    if (action != GLFW_PRESS) return;
    auto* requests = static_cast<key_requests*>(glfwGetWindowUserPointer(window));
    if (key == GLFW_KEY_ESCAPE)
        glfwSetWindowShouldClose(window, GLFW_TRUE);
    else if (key == GLFW_KEY_SPACE)
        requests->toggle_pause = true;
    else if (key == GLFW_KEY_P)
        requests->screenshot = true;
}

int run_window(viewer& v, example::gl_window& window, example::progressive_frame& frame)
{
    constexpr std::uint32_t most_samples = 4096;
    key_requests keys;
    glfwSetWindowUserPointer(window.handle(), &keys);
    glfwSetKeyCallback(window.handle(), on_key);
    glfwSwapInterval(1);
    example::shadertoy_mouse mouse;
    example::shadertoy_inputs in;
    bool paused = false;
    float time = v.o.time;
    clock_type::time_point last = clock_type::now(), title_at = last;
    double drawing_ms = 0;
    int drawn = 0, frame_number = 0;
    std::string shown_error;
    while (!window.should_close()) {
        glfwPollEvents();
        const clock_type::time_point now = clock_type::now();
        const float delta = float(std::chrono::duration<double>(now - last).count());
        last = now;
        if (keys.toggle_pause) paused = !paused, keys.toggle_pause = false;
        if (v.poll()) frame_number = 0, frame.reset();

        const auto [width, height] = window.framebuffer_size();
        if (width < 1 || height < 1) { // minimized: nothing to draw into
            glfwWaitEvents();
            continue;
        }
        frame.resize(width, height);
        const auto [x, y] = window.pointer();
        mouse.update(glfwGetMouseButton(window.handle(), GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS, x,
                     y);
        if (!paused) time += delta;
        // Still (paused, and the pointer's iMouse as it was): one more sample of the same frame.
        // (A new size or program has already dropped the samples.)
        const bool still = paused && !mouse.dragging() && mouse.value() == in.mouse;
        if (!still) frame.reset();
        in.width = float(width), in.height = float(height);
        in.time = time;
        in.time_delta = paused ? 0.0f : delta;
        in.frame = frame_number++;
        in.mouse = mouse.value();
        // A still frame stops at most_samples: the mean has converged, and its float sum's rounding
        // (each addition off by at most half an ulp of a sum <= 4096, 2^-13) leaves the mean within
        // 2^-13 of exact, a thirtieth of a byte's step.
        if (v.program && frame.samples() < most_samples) {
            drawing_ms += draw_sample(v, frame, in);
            ++drawn;
        }
        frame.show(width, height);
        glfwSwapBuffers(window.handle());

        if (keys.screenshot) {
            keys.screenshot = false;
            write_frame(frame, v.o.screenshot);
        }
        if (milliseconds_since(title_at) > 500.0 || shown_error != v.error) {
            char title[512];
            std::snprintf(
                title, sizeof title, "krs_view: %s - %dx%d - %.1f ms per frame%s - %u sample%s",
                v.name.c_str(), width, height, drawn > 0 ? drawing_ms / drawn : 0.0,
                paused ? " - paused" : "", frame.samples(), frame.samples() == 1 ? "" : "s");
            window.set_title(v.error.empty()
                                 ? title
                                 : std::string(title) + " - compile error: " + first_line(v.error));
            shown_error = v.error;
            title_at = clock_type::now();
            drawing_ms = 0, drawn = 0;
        }
    }
    return 0;
}

} // namespace

int main(int argc, char** argv)
{
    const options o = parse(argc, argv);
    viewer v{o, o.glsl.empty() ? o.scene : o.glsl, {}, {}, {}, 0, 0};
    std::string text;
    try {
        if (o.glsl.empty()) text = scene_program(o.scene, o.seed);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "krs_view: %s\n", example::message_of(e).c_str());
        return 1;
    }
    try {
        example::gl_window window("krs_view: " + v.name, o.width, o.height, !o.headless());
        example::progressive_frame frame;
        if (o.glsl.empty()) {
            v.load(text);
        } else {
            v.watch.emplace(o.glsl);
            v.poll();
            if (!v.program && !v.error.empty() && o.reload_seconds > 0)
                std::fprintf(stderr, "krs_view: waiting up to %g s for %s to change\n",
                             double(o.reload_seconds), o.glsl.c_str());
        }
        if (o.headless()) return run_headless(v, frame);
        return run_window(v, window, frame);
    } catch (const example::window_error& e) {
        std::fprintf(stderr,
                     "krs_view: cannot open a window: %s; run under xvfb-run or with a display\n",
                     e.what());
        return 1;
    }
}
