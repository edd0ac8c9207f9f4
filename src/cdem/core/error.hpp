// Errors a user can act on: every input error names where (file, key or item) and what was
// expected. Thrown at set-up; the run loop reports instabilities through RunDiagnosis instead.
#pragma once
#include <stdexcept>
#include <string>

namespace cdem {

class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& what) : std::runtime_error(what) {}
};

class MeshError : public InputError {
 public:
  explicit MeshError(const std::string& what) : InputError(what) {}
};

}  // namespace cdem
