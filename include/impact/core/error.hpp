// SPDX-License-Identifier: MIT
/// \file
/// The one exception type of the library: thrown at validated entry points (mesh construction,
/// tree building from user arrays, loading files, scene edits) with a message giving the reason.
#pragma once

#include <stdexcept>
#include <string>

namespace impact {

/// Invalid input detected at an entry point: NaN or infinite coordinates, out-of-range indices,
/// empty meshes, unreadable files, unknown ids. The message says what and where.
class InvalidInput : public std::invalid_argument {
 public:
  explicit InvalidInput(const std::string& what) : std::invalid_argument("impact: " + what) {}
};

}  // namespace impact
