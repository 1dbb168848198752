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

/// Bad usage of a program: a flag's value that is malformed, out of its range or outside what the
/// shot allows (a --frames range past the shot's frames). The stages exit 2 on it, as on the
/// argument parser's errors, and 1 on other InputErrors.
class UsageError : public InputError {
public:
    using InputError::InputError;
};

/// A failure while running on valid input, with its context (frame, substep, particle, state).
class RuntimeError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

}  // namespace mudcrack
