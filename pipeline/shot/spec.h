#pragma once
/// The shot spec (docs/architecture.md §4): one table with every key of a shot file, its type,
/// default, range, units and one-line doc (polyfem's spec, MuJoCo's single source of truth). The
/// table drives validation, defaults, `mc-shot keys` and which keys each stage's slice holds.
/// Internal to pipeline/shot; other modules use shot.h.
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace mudcrack::spec {

enum class KeyType {
    Section,  // a JSON object holding further keys
    Number,   // any finite number
    Integer,  // a whole number
    Bool,
    String,
    Path,   // a file path, resolved relative to the shot file's folder
    Enum,   // one of `choices`
    Vec3,   // [x, y, z] numbers
    Vec2,   // [a, b] numbers
    Vec2i,  // [a, b] whole numbers
};

/// What happens when a key is absent (its section being present).
enum class Presence {
    Default,   // the default value is filled in (a Section: an empty section is created)
    Required,  // an error
    Derived,   // computed from other keys; the doc says how
    Optional,  // stays absent: the feature (or override) is off
};

/// One end of a range; vectors check it per component.
struct Bound {
    double value;
    bool is_exclusive;
};

struct KeySpec {
    std::string pointer;  // JSON pointer, e.g. "/material/youngs_modulus"
    KeyType type;
    Presence presence;
    nlohmann::json default_value;      // for Presence::Default leaves
    std::vector<std::string> choices;  // for KeyType::Enum
    /// Enum values users will try that are refused on purpose: {value, why not}.
    std::vector<std::pair<std::string, std::string>> refused;
    std::optional<Bound> min, max;
    std::string units;  // "Pa", "m", "-" (dimensionless), "" (not a quantity)
    std::string doc;    // one line
};

/// The table, parents before children.
const std::vector<KeySpec>& table();

/// The entry for `pointer`, or nullptr if the spec has no such key.
const KeySpec* find(const std::string& pointer);

/// "number", "enum(sticky|slip|separate)", "vec3", ...
std::string type_text(const KeySpec& key);
/// "2000", "required", "derived", "(unset)", "on", "off if omitted", ...
std::string default_text(const KeySpec& key);
/// "> 0", "[0, 1)", "(-1, 0.5)", or "" for no range.
std::string range_text(const KeySpec& key);

/// The parent pointer of `pointer` ("" for top-level keys).
std::string parent_of(const std::string& pointer);

}  // namespace mudcrack::spec
