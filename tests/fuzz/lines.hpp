// The lines of a harness's input, without their '\n' (the last one may lack
// it): what a JSON-lines reader of the tool under test would be given.
#pragma once

#include <cstddef>
#include <string_view>

namespace rvc::fuzz {

template <class F>
void for_each_line(std::string_view text, F&& on_line) {
  for (size_t start = 0; start < text.size();) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    on_line(text.substr(start, end - start));
    start = end + 1;
  }
}

}  // namespace rvc::fuzz
