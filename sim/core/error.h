#pragma once
/// Typed exceptions. Libraries throw, they never exit (OpenVDB's rule); only a `main` catches,
/// prints one line and returns 1.
#include <stdexcept>
#include <string>

namespace mudcrack {

/// Bad input from the user: a shot key, a mesh, a cache. The message names the file, the key
/// (JSON pointer) or the record, the value, and what was expected.
class InputError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// A failure while running on valid input, with its context (frame, substep, particle, state).
class RuntimeError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

}  // namespace mudcrack
