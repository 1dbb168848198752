#pragma once
/// Reading a shot file's JSON text. Comments are allowed (docs/architecture.md §4: TDs annotate
/// shots), and what nlohmann's parser accepts silently is refused: a key written twice in one
/// object, where the parser would keep the last value and drop the first without a word. Internal
/// to pipeline/shot.
#include <string>

#include <nlohmann/json.hpp>

#include "pipeline/shot/validate.h"

namespace mudcrack::spec {

/// Parses `text` (comments allowed) into a tree. Every key written twice in the same object is
/// recorded in `issues` as "<file>: <pointer> = <second value>: duplicate key ... <first value>";
/// the tree keeps the second, so the other checks still run.
/// @throws InputError "<file>:<line>:<column>: malformed JSON ..." on a syntax error
nlohmann::json read_shot_json(const std::string& text, Issues& issues);

}  // namespace mudcrack::spec
