// The one exception type for user-facing errors: bad parameters, bad input files, bad state.
#pragma once
#include <stdexcept>
#include <string>

namespace fountain {

// Thrown for problems a user can fix (a key, a file, a particle); the message says which.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace fountain
