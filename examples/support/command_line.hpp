#pragma once
// The examples' command line: CLI11 (Debian's libcli11-dev) with one convention for every
// example, so a user who mistypes learns the same thing from each of them.
//
// - A number is read whole, in decimal: "3x", "2.5" for an integer, "1e9" beyond an integer's
//   range, an empty value, and NaN or infinity for a real number are refused (a parser that takes
//   a number's prefix renders something other than what was asked, without a word).
// - Every refusal names the option, the value given and what is allowed, e.g.
//   "hypertree_render: --supersampling: '17' is not auto or an integer in [1, 16]".
// - A bad command line exits with status 2 before any work starts; -h and --help print the
//   options on stdout and exit with status 0; an option given twice or not known is refused.
//
// The checks are CLI11 validators that run on the text before CLI11 converts it. The integer
// checks also rewrite the text in plain decimal (so they are transforms: CLI11's check() keeps
// the text as given), because CLI11 2.1 converts integers with base 0 ("010" would be 8, "0x10"
// 16) and what the check accepted must be what the program gets.

#include <CLI/CLI.hpp>

#include <charconv>
#include <cmath>
#include <concepts>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace example {

namespace detail {

// "[lo, hi]" or "(lo, hi]": the range as a message shows it.
inline std::string range_text(double lo, double hi, bool lo_open)
{
    const auto number = [](double v) {
        std::string s = std::to_string(v);
        s.erase(s.find_last_not_of('0') + 1); // 4.000000 -> 4. -> 4
        if (s.back() == '.') s.pop_back();
        return s;
    };
    return (lo_open ? "(" : "[") + number(lo) + ", " + number(hi) + "]";
}

// The whole text as a decimal integer, or false (a prefix, a fraction or an exponent is not one).
inline bool whole_integer(std::string_view text, long long& value)
{
    // from_chars takes no '+': drop one, but never before another sign ("+-5" is not a number)
    if (text.size() > 1 && text.front() == '+' && text[1] != '-' && text[1] != '+') text.remove_prefix(1);
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    return error == std::errc() && end == text.data() + text.size() && !text.empty();
}

} // namespace detail

class command_line {
public:
    // `program` is the name messages start with; `description` heads the --help text.
    command_line(std::string program, std::string description) : app_(std::move(description), program), program_(std::move(program))
    {
        app_.option_defaults()->always_capture_default();
    }

    // An integer option in [lo, hi].
    template <std::integral I>
    CLI::Option* integer(const std::string& name, I& value, long long lo, long long hi, const std::string& help)
    {
        return app_.add_option(name, value, help)
            ->type_name("INT" + detail::range_text(double(lo), double(hi), false))
            ->transform(integer_in(lo, hi, "", 0));
    }

    // An integer option in [lo, hi] that also takes one word standing for `word_value` (e.g.
    // --supersampling auto, stored as 0).
    template <std::integral I>
    CLI::Option* integer_or_word(const std::string& name, I& value, long long lo, long long hi, const std::string& word,
                                 I word_value, const std::string& help)
    {
        CLI::Option* option = app_.add_option(name, value, help);
        if (value == word_value) option->default_str(word); // --help shows "auto", not 0
        return option->type_name(word + "|INT" + detail::range_text(double(lo), double(hi), false))
            ->transform(integer_in(lo, hi, word, (long long)word_value));
    }

    // A finite real option in [lo, hi], or (lo, hi] when `lo_open` (a scale that must be positive).
    template <std::floating_point F>
    CLI::Option* number(const std::string& name, F& value, double lo, double hi, bool lo_open, const std::string& help)
    {
        const std::string allowed = "a finite number in " + detail::range_text(lo, hi, lo_open);
        return app_.add_option(name, value, help)
            ->type_name("NUMBER" + detail::range_text(lo, hi, lo_open))
            ->check(CLI::Validator(
                [allowed, lo, hi, lo_open](std::string& text) {
                    double parsed = 0;
                    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), parsed);
                    const bool whole = error == std::errc() && end == text.data() + text.size() && !text.empty();
                    // The range is checked on the value the program gets, rounded to F: 1e-50 is
                    // positive as a double and 0 as a float.
                    const double x = double(static_cast<F>(parsed));
                    // !(x >= lo) and !(x <= hi) so that NaN, which compares false, is refused too
                    if (!whole || !std::isfinite(parsed) || !std::isfinite(x) || (lo_open ? !(x > lo) : !(x >= lo)) ||
                        !(x <= hi))
                        return refusal(text, allowed);
                    return std::string();
                },
                "", "number"));
    }

    // A word from `allowed`.
    CLI::Option* choice(const std::string& name, std::string& value, std::vector<std::string> allowed,
                        const std::string& help)
    {
        std::string listed;
        for (const std::string& a : allowed) listed += (listed.empty() ? "" : "|") + a;
        return app_.add_option(name, value, help)
            ->type_name(listed)
            ->check(CLI::Validator(
                [allowed, listed](std::string& text) {
                    for (const std::string& a : allowed)
                        if (text == a) return std::string();
                    return refusal(text, "one of " + listed);
                },
                "", "choice"));
    }

    // Any text but an empty one or one that starts with "--": CLI11 would take the next option's
    // name as the value ("--output --width 5" writing a file named --width).
    CLI::Option* text(const std::string& name, std::string& value, const std::string& help,
                      const std::string& type = "TEXT")
    {
        return app_.add_option(name, value, help)
            ->type_name(type)
            ->check(CLI::Validator(
                [](std::string& text) {
                    if (text.empty() || text.starts_with("--")) return refusal(text, "a value (not empty, not an option)");
                    return std::string();
                },
                "", "text"));
    }

    // Parses argv. --help prints the options and exits with status 0; a refusal exits with 2.
    void parse(int argc, char** argv)
    {
        try {
            app_.parse(argc, argv);
        } catch (const CLI::CallForHelp& help) {
            std::exit(app_.exit(help));
        } catch (const CLI::ParseError& error) {
            fail(error.what());
        }
    }

    // Refuses the command line for a reason found after parsing (options that exclude each other).
    [[noreturn]] void fail(const std::string& why) const
    {
        std::fprintf(stderr, "%s: %s\nRun '%s --help' for the options.\n", program_.c_str(), why.c_str(), program_.c_str());
        std::exit(2);
    }

    const std::string& program() const { return program_; }
    CLI::App& app() { return app_; }

private:
    // The check of integer(): the whole text a decimal integer in [lo, hi] (or `word`, when not
    // empty, standing for word_value), rewritten in plain decimal for CLI11 to convert.
    static CLI::Validator integer_in(long long lo, long long hi, const std::string& word, long long word_value)
    {
        const std::string allowed =
            (word.empty() ? "" : word + " or ") + "an integer in " + detail::range_text(double(lo), double(hi), false);
        return CLI::Validator(
            [allowed, lo, hi, word, word_value](std::string& text) {
                long long n = 0;
                if (!word.empty() && text == word) n = word_value;
                else if (!detail::whole_integer(text, n) || n < lo || n > hi) return refusal(text, allowed);
                text = std::to_string(n);
                return std::string();
            },
            "", "integer");
    }
    // CLI11 puts the option's name in front ("--width: ...").
    static std::string refusal(const std::string& text, const std::string& allowed)
    {
        return "'" + text + "' is not " + allowed;
    }

    CLI::App app_;
    std::string program_;
};

} // namespace example
