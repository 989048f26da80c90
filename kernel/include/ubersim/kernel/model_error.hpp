// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <stdexcept>
#include <string>

namespace ubersim::kernel {

/// An error in a model file, saying where (file, line, column, key path) and why.
class ModelError : public std::runtime_error {
 public:
  /// line/column are 1-based; 0 when unknown (e.g. a missing file). key is the dotted path
  /// ("drive.wheels[2].angle_deg"), empty for the whole file.
  ModelError(std::string file, int line, int column, std::string key, std::string reason);

  const std::string& file() const { return file_; }      ///< model file path
  int line() const { return line_; }                     ///< 1-based line, 0 unknown
  int column() const { return column_; }                 ///< 1-based column, 0 unknown
  const std::string& key() const { return key_; }        ///< key path
  const std::string& reason() const { return reason_; }  ///< what is wrong

 private:
  std::string file_;
  int line_;
  int column_;
  std::string key_;
  std::string reason_;
};

}  // namespace ubersim::kernel
