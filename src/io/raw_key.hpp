// Raw JSON keys as simdjson hands them over: a pointer to the first byte
// after the opening quote, into the message's own text.
#pragma once

#include <cstddef>

namespace rvc::io {

// Length of a raw key: the bytes before its closing quote. A backslash
// escapes the byte after it, so `\\"` (an escaped backslash, then the quote)
// ends the key: looking only at the byte before a quote would read past it.
inline size_t raw_key_length(const char* k) {
  size_t n = 0;
  while (k[n] != '"') n += k[n] == '\\' ? 2 : 1;
  return n;
}

}  // namespace rvc::io
