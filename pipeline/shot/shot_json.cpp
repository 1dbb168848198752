#include "pipeline/shot/shot_json.h"

#include <utility>
#include <vector>

#include "sim/core/error.h"

namespace mudcrack::spec {
namespace {

using nlohmann::json;

// No shot nests deeper than a few levels; a hostile file nested thousands deep would cost memory
// quadratic in its depth here (each level's pointer) and recursion later (dump, destruction).
constexpr size_t kMaxDepth = 64;

// nlohmann's parse_error text: "[json.exception.parse_error.101] parse error at line 3, column 5:
// ..."
bool split_parse_error(const std::string& what, std::string& line, std::string& column,
                       std::string& rest) {
    const size_t at = what.find("line ");
    if (at == std::string::npos) return false;
    const size_t comma = what.find(", column ", at);
    const size_t colon = comma == std::string::npos ? comma : what.find(": ", comma);
    if (colon == std::string::npos) return false;
    line = what.substr(at + 5, comma - at - 5);
    column = what.substr(comma + 9, colon - comma - 9);
    rest = what.substr(colon + 2);
    // the message quotes the token read so far: a runaway string would make it the whole file
    constexpr size_t kMaxRest = 200;
    if (rest.size() > kMaxRest) rest = rest.substr(0, kMaxRest) + "...";
    const auto is_number = [](const std::string& t) {
        return !t.empty() && t.find_first_not_of("0123456789") == std::string::npos;
    };
    return is_number(line) && is_number(column);
}

// Builds the tree from nlohmann's SAX events, as its own DOM parser does, and in addition knows
// each value's JSON pointer, so a key seen twice in one object is reported with both values.
class DuplicateKeyCheckingBuilder {
public:
    explicit DuplicateKeyCheckingBuilder(Issues& issues) : m_issues(issues) {}

    json take_root() { return std::move(m_root); }

    // SAX events (nlohmann::json_sax)
    bool null() { return add(json(nullptr)); }
    bool boolean(bool v) { return add(json(v)); }
    bool number_integer(json::number_integer_t v) { return add(json(v)); }
    bool number_unsigned(json::number_unsigned_t v) { return add(json(v)); }
    bool number_float(json::number_float_t v, const json::string_t&) { return add(json(v)); }
    bool string(json::string_t& v) { return add(json(std::move(v))); }
    bool binary(json::binary_t& v) { return add(json(std::move(v))); }
    bool start_object(std::size_t) { return open(json::object()); }
    bool start_array(std::size_t) { return open(json::array()); }
    bool end_object() { return close(); }
    bool end_array() { return close(); }

    bool key(json::string_t& name) {
        Container& c = m_open.back();
        c.key = name;
        const auto earlier = c.value->find(name);
        c.is_duplicate_key = earlier != c.value->end();
        c.earlier_text = c.is_duplicate_key ? value_text(&*earlier) : std::string();
        return true;
    }

    // rethrown with its own type, so the caller's catch of json::parse_error sees it; a number
    // too large for a double (nlohmann's out_of_range 406, "1e400") is named by its key here,
    // where the key is known
    template <class Exception>
    bool parse_error(std::size_t, const std::string& token, const Exception& e) {
        if (e.id == kNumberOverflow)
            throw InputError(
                m_issues.file() + ": " + pointer_of_next_value() + " = " + token.substr(0, 40) +
                ": number overflow: expected a number a double holds (magnitude below 1.8e308)");
        throw e;
    }

private:
    struct Container {
        json* value = nullptr;  // the object or array being filled
        std::string pointer;    // its JSON pointer ("" for the root)
        std::string key;        // object: the key of the member being read
        bool is_duplicate_key = false;
        std::string earlier_text;  // the value the object already holds at `key`
    };

    static constexpr int kNumberOverflow = 406;

    // the JSON pointer the value being read will have
    std::string pointer_of_next_value() const {
        if (m_open.empty()) return "(the root)";
        const Container& c = m_open.back();
        return c.pointer + "/" +
               (c.value->is_array() ? std::to_string(c.value->size()) : escape_key(c.key));
    }

    // places a value in the innermost open container (or as the root); returns where it lives
    json* place(json v) {
        if (m_open.empty()) {
            m_root = std::move(v);
            return &m_root;
        }
        Container& c = m_open.back();
        if (c.value->is_array()) {
            c.value->push_back(std::move(v));
            return &c.value->back();
        }
        json& member = (*c.value)[c.key];
        member = std::move(v);
        return &member;
    }

    // a member's value is complete: report it if its key was already set in this object
    void finish_member(const json& v) {
        if (m_open.empty()) return;
        const Container& c = m_open.back();
        if (!c.value->is_object() || !c.is_duplicate_key) return;
        m_issues.add(c.pointer + "/" + escape_key(c.key), value_text(&v),
                     "duplicate key: the same object sets it earlier to " + c.earlier_text +
                         ", and only one value can hold; write the key once");
    }

    bool add(json v) {
        finish_member(*place(std::move(v)));
        return true;
    }

    bool open(json empty) {
        if (m_open.size() >= kMaxDepth)
            throw InputError(m_issues.file() + ": JSON nested deeper than " +
                             std::to_string(kMaxDepth) + " levels: a shot is a few levels deep");
        std::string pointer = m_open.empty() ? std::string() : pointer_of_next_value();
        Container c;
        c.value = place(std::move(empty));
        c.pointer = std::move(pointer);
        m_open.push_back(std::move(c));
        return true;
    }

    bool close() {
        const json* done = m_open.back().value;
        m_open.pop_back();
        finish_member(*done);
        return true;
    }

    Issues& m_issues;
    json m_root;
    std::vector<Container> m_open;  // the containers being read, outermost first
};

}  // namespace

json read_shot_json(const std::string& text, Issues& issues) {
    DuplicateKeyCheckingBuilder builder(issues);
    try {
        json::sax_parse(text, &builder, json::input_format_t::json, /*strict=*/true,
                        /*ignore_comments=*/true);
    } catch (const json::parse_error& e) {
        // nlohmann says "[json.exception.parse_error.101] parse error at line 3, column 5: ..."
        // (no std::regex: its recursive matcher overflows the stack on a long message)
        const std::string what = e.what();
        std::string line, column, rest;
        if (split_parse_error(what, line, column, rest))
            throw InputError(issues.file() + ":" + line + ":" + column + ": malformed JSON (line " +
                             line + ", column " + column + "): " + rest);
        throw InputError(issues.file() + ": malformed JSON: " + what);
    }
    return builder.take_root();
}

}  // namespace mudcrack::spec
