// A specification error that points at a column, rendered like a compiler:
//   spec error at column 9: expected ']' to close the time bounds
//     once[:2 {p}
//             ^
#pragma once

#include <stdexcept>
#include <string>

namespace rvc::spec {

class SpecError : public std::runtime_error {
 public:
  SpecError(std::string message, std::string source, int column)
      : std::runtime_error(render(message, source, column)), message_(std::move(message)),
        source_(std::move(source)), column_(column) {}

  const std::string& message() const { return message_; }  // without the caret picture
  int column() const { return column_; }                     // 1-based
  const std::string& source() const { return source_; }

 private:
  static std::string render(const std::string& message, const std::string& source, int column);
  std::string message_, source_;
  int column_;
};

}  // namespace rvc::spec
