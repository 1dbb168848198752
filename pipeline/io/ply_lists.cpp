#include "pipeline/io/ply_lists.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <fstream>
#include <iterator>
#include <utility>

#include "sim/core/error.h"

namespace fs = std::filesystem;

namespace mudcrack {

PlyType ply_type(const std::string& name) {
    static const std::pair<const char*, PlyType> kTypes[] = {
        {"char", {1, true, false, 127}},
        {"int8", {1, true, false, 127}},
        {"uchar", {1, false, false, 255}},
        {"uint8", {1, false, false, 255}},
        {"short", {2, true, false, 32767}},
        {"int16", {2, true, false, 32767}},
        {"ushort", {2, false, false, 65535}},
        {"uint16", {2, false, false, 65535}},
        {"int", {4, true, false, 2147483647}},
        {"int32", {4, true, false, 2147483647}},
        {"uint", {4, false, false, 4294967295u}},
        {"uint32", {4, false, false, 4294967295u}},
        {"float", {4, true, true, 0}},
        {"float32", {4, true, true, 0}},
        {"double", {8, true, true, 0}},
        {"float64", {8, true, true, 0}}};
    for (const auto& [n, t] : kTypes)
        if (name == n) return t;
    return {};
}

namespace {

[[noreturn]] void refuse(const fs::path& path, const PlyElement& element, uint64_t instance,
                         const std::string& why) {
    throw InputError(path.string() + ": malformed PLY body: element '" + element.name + "' " +
                     std::to_string(instance) + ": " + why);
}

void check_count(const fs::path& path, const PlyElement& element, uint64_t instance,
                 const PlyType& type, int64_t count, uint64_t left) {
    if (count < 0)
        refuse(path, element, instance, "list count " + std::to_string(count) + " is negative");
    if (uint64_t(count) > type.max)
        refuse(path, element, instance,
               "list count " + std::to_string(count) + " does not fit its type");
    if (uint64_t(count) > left)
        refuse(path, element, instance,
               "list count " + std::to_string(count) + ", more than the " + std::to_string(left) +
                   " bytes left in the file");
}

// ---- binary: exact ----

int64_t read_integer(const char* p, const PlyType& type, bool big_endian) {
    // the bytes from the most significant down, in the file's byte order
    const auto* b = reinterpret_cast<const unsigned char*>(p);
    uint64_t u = 0;
    for (size_t k = 0; k < type.bytes; ++k) u = (u << 8) | b[big_endian ? k : type.bytes - 1 - k];
    if (type.is_signed && (u >> (8 * type.bytes - 1)) != 0)
        return int64_t(u) - (int64_t(1) << (8 * type.bytes));
    return int64_t(u);
}

void walk_binary(const fs::path& path, const std::string& body, bool big_endian,
                 const std::vector<PlyElement>& elements) {
    size_t at = 0;
    for (const PlyElement& element : elements) {
        if (element.properties.empty()) continue;  // takes no byte
        for (uint64_t i = 0; i < element.count; ++i) {
            for (const PlyProperty& property : element.properties) {
                const PlyType item = ply_type(property.type);
                if (!property.is_list) {
                    if (item.bytes > body.size() - at)
                        refuse(path, element, i, "the file ends inside it");
                    at += item.bytes;
                    continue;
                }
                const PlyType count_type = ply_type(property.count_type);
                if (count_type.bytes > body.size() - at)
                    refuse(path, element, i, "the file ends inside it");
                const int64_t count = read_integer(&body[at], count_type, big_endian);
                at += count_type.bytes;
                check_count(path, element, i, count_type, count, (body.size() - at) / item.bytes);
                at += size_t(count) * item.bytes;
            }
        }
    }
}

// ---- ASCII: assimp's lines and number syntax ----

bool is_line_end(char c) { return c == '\r' || c == '\n' || c == '\0' || c == '\f'; }
bool is_digit(char c) { return c >= '0' && c <= '9'; }

// assimp's IOStreamBuffer::getNextLine: a line ends at CR, LF, NUL or FF; the next line starts
// after the next LF
class AsciiLines {
public:
    AsciiLines(const std::string& text, size_t start) : m_text(text), m_at(start) {}
    bool next(std::string& line) {
        if (m_at >= m_text.size()) return false;
        if (is_line_end(m_text[m_at])) {
            while (m_at < m_text.size() && m_text[m_at] != '\n') ++m_at;
            ++m_at;
            if (m_at >= m_text.size()) return false;
        }
        const size_t begin = m_at;
        while (m_at < m_text.size() && !is_line_end(m_text[m_at])) ++m_at;
        line.assign(m_text, begin, m_at - begin);
        return true;
    }

private:
    const std::string& m_text;
    size_t m_at;
};

// assimp's SkipSpaces: false at the end of the line
bool skip_spaces(const std::string& line, size_t& at) {
    while (at < line.size() && (line[at] == ' ' || line[at] == '\t')) ++at;
    return at < line.size();
}

// assimp's strtoul10 / strtol10 as its PLY parser reads an integer (32-bit, wrapping)
int64_t parse_integer(const std::string& line, size_t& at, bool is_signed) {
    bool negative = false;
    if (is_signed && at < line.size() && (line[at] == '-' || line[at] == '+'))
        negative = line[at++] == '-';
    uint32_t value = 0;
    while (at < line.size() && is_digit(line[at])) value = value * 10u + uint32_t(line[at++] - '0');
    if (!is_signed) return int64_t(value);
    const int32_t v = int32_t(value);
    return negative ? -int64_t(v) : int64_t(v);
}

bool starts_with_nocase(const std::string& line, size_t at, const char* word) {
    const size_t n = std::strlen(word);
    if (line.size() - at < n) return false;
    for (size_t k = 0; k < n; ++k)
        if (std::tolower(static_cast<unsigned char>(line[at + k])) != word[k]) return false;
    return true;
}

// assimp's fast_atoreal_move: the characters it takes for a real; false where it would throw
bool skip_real(const std::string& line, size_t& at) {
    auto digit_at = [&](size_t k) { return k < line.size() && is_digit(line[k]); };
    auto char_at = [&](size_t k) { return k < line.size() ? line[k] : '\0'; };
    if (char_at(at) == '-' || char_at(at) == '+') ++at;
    if (starts_with_nocase(line, at, "nan")) {
        at += 3;
        return true;
    }
    if (starts_with_nocase(line, at, "inf")) {
        at += 3;
        if (starts_with_nocase(line, at, "inity")) at += 5;
        return true;
    }
    const bool point = char_at(at) == '.' || char_at(at) == ',';
    if (!digit_at(at) && !(point && digit_at(at + 1))) return false;
    while (digit_at(at)) ++at;
    if ((char_at(at) == '.' || char_at(at) == ',') && digit_at(at + 1)) {
        ++at;
        while (digit_at(at)) ++at;
    } else if (char_at(at) == '.') {
        ++at;
    }
    if (char_at(at) == 'e' || char_at(at) == 'E') {
        ++at;
        if (char_at(at) == '-' || char_at(at) == '+') ++at;
        while (digit_at(at)) ++at;
    }
    return true;
}

// one value as assimp's PLY parser takes it; false where assimp stops reading the line
bool skip_value(const std::string& line, size_t& at, const PlyType& type) {
    if (!skip_spaces(line, at)) return false;
    if (type.is_float) return skip_real(line, at);
    parse_integer(line, at, type.is_signed);
    return true;
}

void walk_ascii(const fs::path& path, const std::string& text, size_t start,
                const std::vector<PlyElement>& elements) {
    AsciiLines lines(text, start);
    std::string line;
    for (const PlyElement& element : elements) {
        const bool has_list = std::any_of(element.properties.begin(), element.properties.end(),
                                          [](const PlyProperty& p) { return p.is_list; });
        for (uint64_t i = 0; i < element.count; ++i) {
            if (!lines.next(line)) return;  // assimp stops at the end of the file
            if (!has_list) continue;
            size_t at = 0;
            for (const PlyProperty& property : element.properties) {
                const PlyType item = ply_type(property.type);
                if (!property.is_list) {
                    if (!skip_value(line, at, item)) break;
                    continue;
                }
                const PlyType count_type = ply_type(property.count_type);
                if (!skip_spaces(line, at)) break;
                const int64_t count = parse_integer(line, at, count_type.is_signed);
                check_count(path, element, i, count_type, count, text.size() - start);
                // items end at the line's end; an item that takes no character (not a number)
                // leaves every later one taking none either
                bool stuck = false;
                for (int64_t k = 0; k < count && !stuck; ++k) {
                    const size_t before = at;
                    stuck = !skip_value(line, at, item) || at == before;
                }
                if (stuck) break;
            }
        }
    }
}

}  // namespace

void check_ply_list_counts(const fs::path& path, uint64_t body_offset, const std::string& format,
                           const std::vector<PlyElement>& elements) {
    std::ifstream is(path, std::ios::binary);
    std::string text((std::istreambuf_iterator<char>(is)), std::istreambuf_iterator<char>());
    if (body_offset > text.size()) return;
    if (format == "ascii") {
        // assimp starts at the header's last line end
        walk_ascii(path, text, size_t(body_offset) - (body_offset > 0 ? 1 : 0), elements);
    } else {
        walk_binary(path, text.substr(size_t(body_offset)), format == "binary_big_endian",
                    elements);
    }
}

}  // namespace mudcrack
