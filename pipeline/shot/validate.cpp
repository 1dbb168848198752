#include "pipeline/shot/validate.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>

#include "pipeline/shot/spec.h"
#include "sim/core/error.h"

namespace mudcrack::spec {
namespace {

using nlohmann::json;

std::string last_component(const std::string& pointer) {
    return pointer.substr(pointer.rfind('/') + 1);
}

// how far apart two names may be and still be a plausible typo
bool is_close(const std::string& typed, int distance) {
    return distance <= std::max<int>(2, static_cast<int>(typed.size()) / 3);
}

std::string with_units(const std::string& units) {
    return units.empty() || units == "-" ? "" : " [" + units + "]";
}

bool in_range(const KeySpec& key, double v) {
    if (key.min && (key.min->is_exclusive ? !(v > key.min->value) : !(v >= key.min->value)))
        return false;
    if (key.max && (key.max->is_exclusive ? !(v < key.max->value) : !(v <= key.max->value)))
        return false;
    return true;
}

std::string range_expectation(const KeySpec& key) {
    const std::string r = range_text(key);
    return r.front() == '[' || r.front() == '(' ? "must be in " + r : "must be " + r;
}

std::string choices_text(const std::vector<std::string>& choices) {
    std::string s;
    for (size_t i = 0; i < choices.size(); ++i) s += (i ? ", \"" : "\"") + choices[i] + "\"";
    return s;
}

bool is_whole(const json& v) {
    if (v.is_number_integer()) return true;
    if (!v.is_number_float()) return false;
    const double d = v.get<double>();
    return std::isfinite(d) && d == std::floor(d) && std::fabs(d) < 9.0e15;
}

// checks one scalar number against the key's type and range; the normalized value or nullopt
std::optional<json> check_number(const KeySpec& key, const json& v, bool is_integer,
                                 const std::string& pointer, Issues& issues) {
    if (!v.is_number() || (is_integer && !is_whole(v))) {
        issues.add(pointer, value_text(&v), is_integer ? "must be an integer" : "must be a number",
                   key.units);
        return std::nullopt;
    }
    const double d = v.get<double>();
    if (!in_range(key, d)) {
        issues.add(pointer, value_text(&v), range_expectation(key), key.units);
        return std::nullopt;
    }
    // the stages hold integers in an int: a larger one would wrap into another value
    constexpr double kMaxInt = std::numeric_limits<int>::max();
    if (is_integer && !key.max && !(std::fabs(d) <= kMaxInt)) {
        issues.add(pointer, value_text(&v),
                   "must be <= " + std::to_string(int(kMaxInt)) + " (the largest int)", key.units);
        return std::nullopt;
    }
    if (is_integer) return json(static_cast<std::int64_t>(d));
    return json(d);
}

std::optional<json> check_vector(const KeySpec& key, const json& v, size_t n, bool is_integer,
                                 const std::string& pointer, Issues& issues) {
    const bool is_shaped =
        v.is_array() && v.size() == n &&
        std::all_of(v.begin(), v.end(), [](const json& c) { return c.is_number(); });
    if (!is_shaped) {
        const std::string what = n == 3 ? "[x, y, z]" : "[a, b]";
        issues.add(pointer, value_text(&v),
                   "must be an array " + what + " of " + std::to_string(n) +
                       (is_integer ? " integers" : " numbers"),
                   key.units);
        return std::nullopt;
    }
    json out = json::array();
    bool is_ok = true;
    for (size_t i = 0; i < n; ++i) {
        auto c = check_number(key, v[i], is_integer, pointer + "/" + std::to_string(i), issues);
        if (c)
            out.push_back(*c);
        else
            is_ok = false;
    }
    if (!is_ok) return std::nullopt;
    return out;
}

std::optional<json> check_leaf(const KeySpec& key, const json& v, const std::string& pointer,
                               Issues& issues) {
    switch (key.type) {
        case KeyType::Number: return check_number(key, v, false, pointer, issues);
        case KeyType::Integer: return check_number(key, v, true, pointer, issues);
        case KeyType::Vec3: return check_vector(key, v, 3, false, pointer, issues);
        case KeyType::Vec2: return check_vector(key, v, 2, false, pointer, issues);
        case KeyType::Vec2i: return check_vector(key, v, 2, true, pointer, issues);
        case KeyType::Bool:
            if (v.is_boolean()) return v;
            issues.add(pointer, value_text(&v), "must be true or false");
            return std::nullopt;
        case KeyType::String:
            if (v.is_string()) return v;
            issues.add(pointer, value_text(&v), "must be a string");
            return std::nullopt;
        case KeyType::Path:
            if (v.is_string() && !v.get<std::string>().empty()) return v;
            issues.add(pointer, value_text(&v), "must be a non-empty path string");
            return std::nullopt;
        case KeyType::Enum: {
            if (v.is_string()) {
                const std::string s = v.get<std::string>();
                if (std::find(key.choices.begin(), key.choices.end(), s) != key.choices.end())
                    return v;
                for (const auto& [refused, why] : key.refused) {
                    if (s != refused) continue;
                    issues.add(pointer, value_text(&v), why);
                    return std::nullopt;
                }
                issues.add(
                    pointer, value_text(&v),
                    "must be one of " + choices_text(key.choices) + suggest_choice(s, key.choices));
            } else {
                issues.add(pointer, value_text(&v), "must be one of " + choices_text(key.choices));
            }
            return std::nullopt;
        }
        case KeyType::Section: break;  // handled by the caller
    }
    return std::nullopt;
}

// walks one object of the shot: every member must be a known key of the right type
void check_object(const json& in, const std::string& prefix, json& out, Issues& issues) {
    for (const auto& [name, value] : in.items()) {
        const std::string pointer = prefix + "/" + escape_key(name);
        const KeySpec* key = find(pointer);
        if (!key) {
            issues.add(pointer, value_text(&value), "unknown key" + suggest_key(pointer));
            continue;
        }
        if (key->type == KeyType::Section) {
            json section = json::object();
            if (value.is_object())
                check_object(value, pointer, section, issues);
            else
                issues.add(pointer, value_text(&value), "must be an object (a section of keys)");
            out[name] = std::move(section);
            continue;
        }
        if (auto v = check_leaf(*key, value, pointer, issues)) out[name] = std::move(*v);
    }
}

// the section object at `pointer` in `root`, or nullptr if absent
json* section_at(json& root, const std::string& pointer) {
    if (pointer.empty()) return &root;
    const json::json_pointer p(pointer);
    if (!root.contains(p)) return nullptr;
    json& s = root[p];
    return s.is_object() ? &s : nullptr;
}

}  // namespace

std::string escape_key(const std::string& key) {
    std::string out;
    for (char c : key) {
        if (c == '~')
            out += "~0";
        else if (c == '/')
            out += "~1";
        else
            out += c;
    }
    return out;
}

void Issues::add(const std::string& pointer, const std::string& value,
                 const std::string& expectation, const std::string& units) {
    m_lines.push_back(m_file + ": " + pointer + " = " + value + ": " + expectation +
                      with_units(units));
    m_pointers.insert(pointer);
}

bool Issues::has(const std::string& pointer) const {
    if (m_pointers.count(pointer)) return true;
    // the set is sorted, so keys inside `pointer` start at lower_bound(pointer + "/")
    const std::string inside = pointer + "/";
    const auto it = m_pointers.lower_bound(inside);
    return it != m_pointers.end() && it->compare(0, inside.size(), inside) == 0;
}

std::string Issues::value_of(const json& filled, const std::string& pointer) const {
    const json::json_pointer p(pointer);
    if (m_written.is_object() && m_written.contains(p)) return value_text(&m_written.at(p));
    return filled.contains(p) ? value_text(&filled.at(p)) : value_text(nullptr);
}

void Issues::throw_if_any() const {
    if (m_lines.empty()) return;
    std::string msg;
    for (size_t i = 0; i < m_lines.size(); ++i) msg += (i ? "\n" : "") + m_lines[i];
    throw InputError(msg);
}

std::string value_text(const json* value) {
    if (!value) return "(missing)";
    std::string s = value->dump();
    constexpr size_t kMaxChars = 60;
    if (s.size() > kMaxChars) s = s.substr(0, kMaxChars - 3) + "...";
    return s;
}

json check_and_fill(const json& root, Issues& issues) {
    json out = json::object();
    if (!root.is_object()) {
        issues.add("", value_text(&root), "a shot must be a JSON object {\"mudcrack\": 1, ...}");
        return out;
    }
    check_object(root, "", out, issues);

    // fill defaults, parents before children, only inside sections that are on
    for (const KeySpec& key : table()) {
        const std::string parent = parent_of(key.pointer);
        json* section = section_at(out, parent);
        if (!section) continue;  // the section is off (or broken, already reported)
        const std::string name = last_component(key.pointer);
        if (section->contains(name)) continue;
        const bool was_bad = issues.has(key.pointer);
        switch (key.presence) {
            case Presence::Default:
                (*section)[name] =
                    key.type == KeyType::Section ? json::object() : key.default_value;
                break;
            case Presence::Required:
                if (was_bad) break;
                if (key.type == KeyType::Section)
                    issues.add(key.pointer, "(missing)", "required section");
                else if (key.type == KeyType::Enum)
                    issues.add(key.pointer, "(missing)",
                               "required; one of " + choices_text(key.choices));
                else
                    issues.add(key.pointer, "(missing)",
                               "required " + type_text(key) + " (" + key.doc + ")", key.units);
                if (key.type == KeyType::Section) (*section)[name] = json::object();
                break;
            case Presence::Derived:
            case Presence::Optional: break;
        }
    }
    return out;
}

int edit_distance(const std::string& a, const std::string& b) {
    std::vector<int> row(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) row[j] = static_cast<int>(j);
    for (size_t i = 1; i <= a.size(); ++i) {
        int diagonal = row[0];
        row[0] = static_cast<int>(i);
        for (size_t j = 1; j <= b.size(); ++j) {
            const int substitute = diagonal + (a[i - 1] == b[j - 1] ? 0 : 1);
            diagonal = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, substitute});
        }
    }
    return row[b.size()];
}

std::string suggest_key(const std::string& pointer) {
    const std::string parent = parent_of(pointer);
    const std::string name = last_component(pointer);
    const KeySpec* best_local = nullptr;
    const KeySpec* best_global = nullptr;
    int local_distance = 1 << 30, global_distance = 1 << 30;
    for (const KeySpec& key : table()) {
        const int d = edit_distance(name, last_component(key.pointer));
        if (parent_of(key.pointer) == parent && d < local_distance) {
            local_distance = d;
            best_local = &key;
        }
        if (d < global_distance) {
            global_distance = d;
            best_global = &key;
        }
    }
    // the exact name in another section beats a typo in this one; otherwise a close name in
    // this section beats one elsewhere
    if (best_global && global_distance == 0 && local_distance > 0)
        return " (did you mean " + best_global->pointer + "?)";
    if (best_local && is_close(name, local_distance))
        return " (did you mean " + best_local->pointer + "?)";
    if (best_global && is_close(name, global_distance))
        return " (did you mean " + best_global->pointer + "?)";
    return "";
}

std::string suggest_choice(const std::string& value, const std::vector<std::string>& choices) {
    const std::string* best = nullptr;
    int best_distance = 1 << 30;
    for (const std::string& c : choices) {
        const int d = edit_distance(value, c);
        if (d < best_distance) {
            best_distance = d;
            best = &c;
        }
    }
    if (best && is_close(value, best_distance)) return " (did you mean \"" + *best + "\"?)";
    return "";
}

}  // namespace mudcrack::spec
