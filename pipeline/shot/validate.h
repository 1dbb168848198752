#pragma once
/// Checking a parsed shot against the spec table: unknown keys, types, ranges, required keys, and
/// the defaults of every present section. Every problem is collected, so the user sees all of
/// them at once (docs/architecture.md §5, pbrt's ErrorExitDeferred). Internal to pipeline/shot.
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace mudcrack::spec {

/// The problems found in one shot file, reported together.
class Issues {
public:
    explicit Issues(std::string file) : m_file(std::move(file)) {}

    /// Records "<file>: <pointer> = <value>: <expectation> [units]" (no brackets for "" or "-").
    void add(const std::string& pointer, const std::string& value, const std::string& expectation,
             const std::string& units = "");
    /// True if a problem was recorded for `pointer` or for a key inside it (e.g. a component).
    bool has(const std::string& pointer) const;
    bool empty() const { return m_lines.empty(); }
    /// Keeps the shot as written, so messages show values as the user spelled them.
    void set_written(const nlohmann::json& root) { m_written = root; }
    /// The value at `pointer` as written, else as in `filled` (a default), else "(missing)".
    std::string value_of(const nlohmann::json& filled, const std::string& pointer) const;
    const std::vector<std::string>& lines() const { return m_lines; }
    const std::string& file() const { return m_file; }
    /// Throws one InputError holding every problem, one per line, if there is any.
    void throw_if_any() const;

private:
    std::string m_file;
    std::vector<std::string> m_lines;
    std::set<std::string> m_pointers;
    nlohmann::json m_written;
};

/// A key as a JSON pointer token (RFC 6901: a key may hold '~' or '/', written ~0 and ~1).
std::string escape_key(const std::string& key);

/// How a value appears in a message: its JSON text (shortened if long), or "(missing)".
std::string value_text(const nlohmann::json* value);

/// Checks `root` against the spec table and returns a normalized copy: every key of every present
/// section (and of every default-on section) is there, with its default where it was left out;
/// numbers are doubles, integers are int64, so equal values print identically. A key with a bad
/// value is recorded in `issues` and left out of the copy (its default, if it has one, fills
/// in), so later checks can run on the rest.
nlohmann::json check_and_fill(const nlohmann::json& root, Issues& issues);

/// " (did you mean /x/y?)" for an unknown pointer: the nearest key in the same section by edit
/// distance, else the nearest key name anywhere; "" when nothing is close.
std::string suggest_key(const std::string& pointer);

/// " (did you mean \"x\"?)" for a value that is not one of `choices`; "" when nothing is close.
std::string suggest_choice(const std::string& value, const std::vector<std::string>& choices);

/// Levenshtein distance (insert, delete, substitute each cost 1).
int edit_distance(const std::string& a, const std::string& b);

}  // namespace mudcrack::spec
