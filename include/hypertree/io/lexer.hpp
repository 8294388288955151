#pragma once
// Reading the text of definition files (paper section 10): the error every reader throws, the
// tokens, and a cursor over one line's values that turns bad input into a located message.
//
// The files are line based: one keyword and its values per line, `#` starts a comment that runs
// to the end of the line. A line splits into tokens: words (keywords, numbers, axis letters, paths:
// any run of characters that are not blank and not one of `( ) , ~ # "`), the four punctuation
// marks `( ) , ~` of per-level and random values, and "quoted text" (a name or a path with blanks;
// it ends on the same line, without escapes).
//
// Positions are 1-based lines and columns; a column counts bytes from the start of the line, so a
// tab is one column. Every problem is a `definition_error` whose message starts with
// `file:line:column:` like a compiler's, so editors jump to it; the message says what was
// expected and what was found.
//
// Files come from every editor: a line ends at LF, CR LF or a lone CR (old Mac editors, which
// otherwise made the whole file one line), and a UTF-8 byte-order mark at the start (Windows
// editors) is skipped, columns counting from after it. A UTF-16 or UTF-32 mark is refused by name:
// every other byte of such a file is 0, and its first line would read as an unknown keyword.

#include "hypertree/volume.hpp"
#include "krs/core/validate.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace hypertree {

struct source_position {
    int line = 1;
    int column = 1;
    friend bool operator==(const source_position&, const source_position&) = default;
};

// what() is "file:line:column: message"; the parts stay available for tools.
class definition_error : public std::runtime_error {
public:
    definition_error(std::string_view file, source_position at, std::string_view message)
        : std::runtime_error(std::string(file) + ":" + std::to_string(at.line) + ":" + std::to_string(at.column) + ": " +
                             std::string(message)),
          file_(file), at_(at), message_(message)
    {
    }
    const std::string& file() const noexcept { return file_; }
    int line() const noexcept { return at_.line; }
    int column() const noexcept { return at_.column; }
    source_position position() const noexcept { return at_; }
    // The message without its location prefix.
    const std::string& message() const noexcept { return message_; }

private:
    std::string file_;
    source_position at_;
    std::string message_;
};

namespace io {

enum class token_kind { word, quoted, open_paren, close_paren, comma, tilde };

struct token {
    token_kind kind = token_kind::word;
    std::string_view text; // a quoted token's text is what lies between the quotes
    source_position at;
    int width = 0; // bytes the token takes in the source (quotes included)
};

// The tokens of one non-empty line, and where the line's last token ends (where a missing value
// is reported).
struct source_line {
    std::vector<token> tokens;
    source_position end;
};

// A CR is blank where it is the first half of CR LF; a lone CR ends a line (line_break_at).
inline bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }
inline bool ends_word(char c) { return is_blank(c) || c == '\n' || c == '(' || c == ')' || c == ',' || c == '~' || c == '#' || c == '"'; }
// Whether a line ends at text[i]: an LF, or a CR that no LF follows.
inline bool line_break_at(std::string_view text, std::size_t i)
{
    return text[i] == '\n' || (text[i] == '\r' && (i + 1 == text.size() || text[i + 1] != '\n'));
}

// The bytes of a UTF-8 byte-order mark at the start of `text` (0 or 3), skipped by tokenize. A
// mark of UTF-16 or UTF-32 is refused, naming the encoding and what to save the file as.
inline std::size_t byte_order_mark(std::string_view text, std::string_view file)
{
    if (text.starts_with("\xEF\xBB\xBF")) return 3;
    const auto refuse = [&](std::string_view encoding) {
        throw definition_error(file, {1, 1}, "the file is " + std::string(encoding) +
                                                 " (it starts with that byte-order mark); save it as UTF-8 or ASCII");
    };
    using namespace std::string_view_literals;
    if (text.starts_with("\xFF\xFE\0\0"sv) || text.starts_with("\0\0\xFE\xFF"sv)) refuse("UTF-32");
    if (text.starts_with("\xFF\xFE") || text.starts_with("\xFE\xFF")) refuse("UTF-16");
    return 0;
}

inline char ascii_upper(char c) { return c >= 'a' && c <= 'z' ? char(c - 'a' + 'A') : c; }
inline std::string upper(std::string_view s)
{
    std::string u(s);
    for (char& c : u) c = ascii_upper(c);
    return u;
}
// Keywords and named values are case-insensitive (ASCII).
inline bool same_word(std::string_view a, std::string_view b)
{
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
        if (ascii_upper(a[i]) != ascii_upper(b[i])) return false;
    return true;
}

// A token as messages quote it: control and non-ASCII bytes escaped, long tokens cut, so a
// message stays one readable line whatever the file holds.
inline std::string quoted_for_message(std::string_view text)
{
    constexpr std::size_t longest = 40;
    std::string out = "'";
    for (std::size_t i = 0; i < text.size() && i < longest; ++i) {
        const auto c = static_cast<unsigned char>(text[i]);
        if (c >= 0x20 && c < 0x7f) {
            out += char(c);
        } else {
            constexpr char hex[] = "0123456789abcdef";
            out += "\\x";
            out += hex[c >> 4];
            out += hex[c & 15];
        }
    }
    if (text.size() > longest) out += "...";
    return out + "'";
}

inline std::string describe(const token* t)
{
    if (t == nullptr) return "end of line";
    if (t->kind == token_kind::quoted) return "quoted text " + quoted_for_message(t->text);
    return quoted_for_message(t->text);
}

inline std::vector<source_line> tokenize(std::string_view text, std::string_view file)
{
    std::vector<source_line> lines;
    source_line current;
    int line = 1;
    std::size_t line_start = byte_order_mark(text, file);
    const auto position = [&](std::size_t at) {
        // A line longer than an int can count keeps the largest column rather than wrapping.
        const std::size_t column = at - line_start + 1;
        return source_position{line, int(std::min<std::size_t>(column, std::size_t(std::numeric_limits<int>::max())))};
    };
    const auto close_line = [&] {
        if (!current.tokens.empty()) {
            const token& last = current.tokens.back();
            current.end = {last.at.line, last.at.column + last.width};
            lines.push_back(std::move(current));
        }
        current = {};
    };
    std::size_t i = line_start;
    while (i < text.size()) {
        const char c = text[i];
        if (line_break_at(text, i)) {
            close_line();
            if (line < std::numeric_limits<int>::max()) ++line;
            line_start = ++i;
        } else if (is_blank(c)) {
            ++i;
        } else if (c == '#') {
            while (i < text.size() && !line_break_at(text, i)) ++i;
        } else if (c == '(' || c == ')' || c == ',' || c == '~') {
            const token_kind kind = c == '(' ? token_kind::open_paren
                                    : c == ')' ? token_kind::close_paren
                                    : c == ',' ? token_kind::comma
                                               : token_kind::tilde;
            current.tokens.push_back({kind, text.substr(i, 1), position(i), 1});
            ++i;
        } else if (c == '"') {
            // A quote closes on its own line: at the first '"' before any line break (CR included).
            const std::size_t close = text.find_first_of("\"\n\r", i + 1);
            if (close == std::string_view::npos || text[close] != '"')
                throw definition_error(file, position(i), "unterminated quoted text: a '\"' must close it on the same line");
            current.tokens.push_back({token_kind::quoted, text.substr(i + 1, close - i - 1), position(i), int(close - i + 1)});
            i = close + 1;
        } else {
            const std::size_t begin = i;
            while (i < text.size() && !ends_word(text[i])) ++i;
            current.tokens.push_back({token_kind::word, text.substr(begin, i - begin), position(begin), int(i - begin)});
        }
    }
    close_line();
    return lines;
}

// Where the input ends (for "missing" errors that belong to no line).
inline source_position end_of_input(std::string_view text)
{
    source_position at{1, 1};
    for (std::size_t i = text.starts_with("\xEF\xBB\xBF") ? 3 : 0; i < text.size(); ++i) {
        if (line_break_at(text, i)) at = {at.line + 1, 1};
        else ++at.column;
    }
    return at;
}

// The largest definition or forest file read, in bytes (16 MiB). The example files are a few
// kilobytes; the limit is what keeps a wrong path (a 2 GB file, a log) from being read whole into
// memory before the parser refuses its first line.
inline constexpr std::uintmax_t max_text_file_bytes = std::uintmax_t(16) << 20;

// A definition or forest file's text, or why it cannot be read (`problem`, the text then empty).
struct text_file {
    std::string text;
    std::string problem;
};

// Reads `path` whole when it is a regular file of at most max_text_file_bytes. Anything else is
// refused before it is opened: opening a FIFO blocks until a writer comes, and a device such as
// /dev/zero never ends. The limit is checked on the size the file reports and again while reading
// (a file that grows, or one of /proc that reports 0), so at most max_text_file_bytes + 1 bytes
// are read. `problem` gives the system's reason where there is one.
inline text_file read_text_file(const std::filesystem::path& path)
{
    const std::string limit = "the limit of " + std::to_string(max_text_file_bytes) + " bytes (" +
                              std::to_string(max_text_file_bytes >> 20) + " MiB)";
    std::error_code ec;
    const std::filesystem::file_status status = std::filesystem::status(path, ec);
    if (!std::filesystem::exists(status))
        return {{}, ec ? ec.message() : std::string("No such file or directory")};
    if (std::filesystem::is_directory(status)) return {{}, "it is a directory"};
    if (!std::filesystem::is_regular_file(status))
        return {{}, "it is not a regular file (a FIFO, a device or a socket); only regular files are read"};
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (!ec && size > max_text_file_bytes)
        return {{}, "it is " + std::to_string(size) + " bytes, over " + limit};
    errno = 0;
    std::ifstream in(path, std::ios::binary);
    const auto system_reason = [](const char* fallback) {
        return errno != 0 ? std::generic_category().message(errno) : std::string(fallback);
    };
    if (!in) return {{}, system_reason("it cannot be opened")};
    std::string text;
    char block[1 << 16];
    while (in.read(block, sizeof block) || in.gcount() > 0) {
        text.append(block, std::size_t(in.gcount()));
        if (text.size() > max_text_file_bytes) return {{}, "it holds more than " + limit};
    }
    if (in.bad()) return {{}, system_reason("reading it failed")};
    return {std::move(text), {}};
}

// What a number must satisfy beyond being one.
enum class number_rule { any, non_negative, positive, unit_interval };

// Where the two value forms of section 10 may appear (the readers cite these in their messages).
inline constexpr std::string_view per_level_rule =
    ": per-level '(a, b)' and '(a, b, c)' values are allowed only in the TRANSLATE, ROTATE, SCALE and SHEAR lines of a TRANSFORM";
inline constexpr std::string_view random_rule =
    ": random 'mean~spread' values are allowed only in the TRANSLATE, ROTATE, SCALE and SHEAR lines of a TRANSFORM or CONDENSATION";

// A cursor over one line: its keyword, then its values in order. Each reader either returns a
// value or throws a definition_error at the offending token, "expected <what> after KEYWORD, got
// <token>", with the keyword's usage appended when a value is missing or surplus.
class statement {
public:
    statement(std::string_view file, const source_line& line, std::string_view usage)
        : file_(file), line_(line), usage_(usage), keyword_(upper(line.tokens.front().text))
    {
    }

    const std::string& keyword() const { return keyword_; }
    source_position where() const { return line_.tokens.front().at; }
    std::string_view file() const { return file_; }
    bool at_end() const { return next_ >= line_.tokens.size(); }
    const token* peek() const { return at_end() ? nullptr : &line_.tokens[next_]; }
    source_position next_position() const { return at_end() ? line_.end : line_.tokens[next_].at; }

    [[noreturn]] void fail(source_position at, const std::string& message) const { throw definition_error(file_, at, message); }
    [[noreturn]] void fail(const std::string& message) const { fail(where(), message); }

    // "expected <what> after KEYWORD, got <next token>" at the next token (or the line's end).
    [[noreturn]] void expected(std::string_view what, std::string_view context = {}) const
    {
        std::string message = "expected " + std::string(what) + " " +
                              (context.empty() ? "after " + keyword_ : std::string(context)) + ", got " + describe(peek());
        if (at_end() || peek()->kind == token_kind::word) message += " (usage: " + std::string(usage_) + ")";
        fail(next_position(), message);
    }

    // Nothing may follow the values a keyword takes.
    void finish() const
    {
        if (!at_end())
            fail(next_position(), "unexpected " + describe(peek()) + " after " + keyword_ + " (usage: " + std::string(usage_) + ")");
    }

    // A plain number: finite, of magnitude at most krs::max_magnitude (1e9) so that nothing
    // computed from it overflows, and obeying `rule`. Per-level and random forms are refused with
    // a word on where they are allowed.
    double number(number_rule rule = number_rule::any, std::string_view context = {})
    {
        const double v = number_before_spread(rule, context);
        refuse_random_after_plain_value(context);
        return v;
    }
    // The same, where a '~' and a spread may follow (the caller reads them).
    double number_before_spread(number_rule rule = number_rule::any, std::string_view context = {})
    {
        const token* t = peek();
        if (t != nullptr && (t->kind == token_kind::open_paren || t->kind == token_kind::tilde))
            fail(t->at, "expected a plain number " + (context.empty() ? "after " + keyword_ : std::string(context)) + ", got " + describe(t) +
                            std::string(t->kind == token_kind::open_paren ? per_level_rule : random_rule));
        const std::optional<double> v = t != nullptr && t->kind == token_kind::word ? parse_double(t->text) : std::nullopt;
        if (!v) expected("a number", context);
        if (!(std::abs(*v) <= double(krs::max_magnitude)))
            expected("a number of magnitude at most " + std::string(krs::detail::max_magnitude_text), context);
        switch (rule) {
        case number_rule::any: break;
        case number_rule::non_negative:
            if (!(*v >= 0)) expected("a number >= 0", context);
            break;
        case number_rule::positive:
            if (!(*v > 0)) expected("a number > 0", context);
            break;
        case number_rule::unit_interval:
            if (!(*v >= 0 && *v <= 1)) expected("a number in [0, 1]", context);
            break;
        }
        ++next_;
        return *v;
    }

    // A whole number in [lowest, highest], written in decimal digits (an optional sign first).
    long long integer(long long lowest, long long highest, std::string_view context = {})
    {
        const token* t = peek();
        const std::optional<long long> v = t != nullptr && t->kind == token_kind::word ? parse_integer(t->text) : std::nullopt;
        if (!v) expected("an integer", context);
        if (*v < lowest || *v > highest) expected("an integer in [" + std::to_string(lowest) + ", " + std::to_string(highest) + "]", context);
        ++next_;
        refuse_random_after_plain_value(context);
        return *v;
    }

    // A count that may need all 64 bits (ITERATIONS), at least `lowest`.
    std::uint64_t count(std::uint64_t lowest)
    {
        const token* t = peek();
        std::uint64_t v = 0;
        bool ok = t != nullptr && t->kind == token_kind::word && !t->text.empty() && t->text.front() != '-';
        if (ok) {
            const std::string_view digits = t->text.front() == '+' ? t->text.substr(1) : t->text;
            const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), v);
            ok = error == std::errc() && end == digits.data() + digits.size() && !digits.empty();
        }
        if (!ok || v < lowest) expected("an integer >= " + std::to_string(lowest) + " (at most 2^64 - 1)");
        ++next_;
        refuse_random_after_plain_value({});
        return v;
    }

    // One of x, y, z (either case): 0, 1 or 2.
    int axis()
    {
        const token* t = peek();
        if (t != nullptr && t->kind == token_kind::word) {
            constexpr std::string_view names[3] = {"x", "y", "z"};
            for (int a = 0; a < 3; ++a)
                if (same_word(t->text, names[a])) {
                    ++next_;
                    return a;
                }
        }
        expected("an axis (x, y or z)");
    }

    // A word or a quoted text (a name or a path).
    std::string_view text(std::string_view what)
    {
        const token* t = peek();
        if (t == nullptr || (t->kind != token_kind::word && t->kind != token_kind::quoted) || t->text.empty()) expected(what);
        ++next_;
        return t->text;
    }

    // The next token if it is the word `word` (any case), consumed.
    bool accept_word(std::string_view word)
    {
        const token* t = peek();
        if (t == nullptr || t->kind != token_kind::word || !same_word(t->text, word)) return false;
        ++next_;
        return true;
    }

    // The next token, whatever it is (for the readers of compound values).
    const token& take() { return line_.tokens[next_++]; }

    static std::optional<double> parse_double(std::string_view s)
    {
        // from_chars takes no leading '+'; a file may write one (but not "+-1").
        if (!s.empty() && s.front() == '+') {
            s.remove_prefix(1);
            if (s.empty() || s.front() == '+' || s.front() == '-') return std::nullopt;
        }
        double v = 0;
        const auto [end, error] = std::from_chars(s.data(), s.data() + s.size(), v);
        if (error != std::errc() || end != s.data() + s.size() || !std::isfinite(v)) return std::nullopt;
        return v;
    }
    static std::optional<long long> parse_integer(std::string_view s)
    {
        if (!s.empty() && s.front() == '+') {
            s.remove_prefix(1);
            if (s.empty() || s.front() == '+' || s.front() == '-') return std::nullopt;
        }
        long long v = 0;
        const auto [end, error] = std::from_chars(s.data(), s.data() + s.size(), v);
        if (error != std::errc() || end != s.data() + s.size()) return std::nullopt;
        return v;
    }

private:
    // `0.5~0.1` where only a plain number is allowed reads as a number and a stray '~': say why.
    void refuse_random_after_plain_value(std::string_view context) const
    {
        const token* t = peek();
        if (t != nullptr && t->kind == token_kind::tilde)
            fail(t->at, "unexpected '~' " + (context.empty() ? "after " + keyword_ : std::string(context)) + std::string(random_rule));
    }

    std::string_view file_;
    const source_line& line_;
    std::string_view usage_;
    std::string keyword_;
    std::size_t next_ = 1; // token 0 is the keyword
};

// RESOLUTION's values, shared by tree and forest files: one count (a cube) or three, each >= 1,
// at most 2^32 - 1 voxels in all (volume.hpp's 32-bit voxel indices).
inline resolution read_resolution(statement& s)
{
    constexpr long long largest = std::numeric_limits<int>::max();
    const int nx = int(s.integer(1, largest));
    int ny = nx, nz = nx;
    if (!s.at_end()) ny = int(s.integer(1, largest)), nz = int(s.integer(1, largest));
    s.finish();
    // Two factors below 2^31 fit in 64 bits; the third is multiplied only once the first two are
    // known to fit in 32.
    const std::uint64_t xy = std::uint64_t(nx) * std::uint64_t(ny);
    if (xy > max_voxel_count || xy * std::uint64_t(nz) > max_voxel_count)
        s.fail("expected at most " + std::to_string(max_voxel_count) + " voxels (32-bit voxel indices), got RESOLUTION " + std::to_string(nx) +
               " x " + std::to_string(ny) + " x " + std::to_string(nz) + (xy > max_voxel_count ? "" : " = " + std::to_string(xy * std::uint64_t(nz))));
    return {nx, ny, nz};
}

} // namespace io
} // namespace hypertree
