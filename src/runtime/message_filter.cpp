#include "runtime/message_filter.hpp"

#include <stdexcept>

#include "io/json_writer.hpp"

namespace rvc::runtime {
namespace {

std::vector<std::string_view> chunks(std::string_view s) {
  std::vector<std::string_view> out;
  size_t start = 0;
  for (;;) {
    size_t slash = s.find('/', start);
    out.push_back(s.substr(start, slash == std::string_view::npos ? std::string_view::npos : slash - start));
    if (slash == std::string_view::npos) return out;
    start = slash + 1;
  }
}

bool match_chunks(const std::vector<std::string_view>& p, size_t i, const std::vector<std::string_view>& k, size_t j) {
  for (; i < p.size(); ++i, ++j) {
    if (p[i] == "**") {
      // Any number of chunks: try every split (patterns are short).
      for (size_t rest = j; rest <= k.size(); ++rest)
        if (match_chunks(p, i + 1, k, rest)) return true;
      return false;
    }
    if (j >= k.size()) return false;
    if (p[i] != "*" && p[i] != k[j]) return false;
  }
  return j == k.size();
}

}  // namespace

bool key_matches(std::string_view pattern, std::string_view key) {
  // A leading '/' (DDS topics, ROS names) is not a chunk of its own.
  if (!pattern.empty() && pattern[0] == '/') pattern.remove_prefix(1);
  if (!key.empty() && key[0] == '/') key.remove_prefix(1);
  return match_chunks(chunks(pattern), 0, chunks(key), 0);
}

MessageFilter::MessageFilter(FilterOptions options) : options_(std::move(options)) {
  for (const auto* list : {&options_.allow, &options_.deny})
    for (const auto& p : *list)
      if (p.empty()) throw std::invalid_argument("--allow/--deny: empty key pattern");
  for (const auto& path : options_.project) {
    std::vector<std::string> parts;
    size_t start = 0;
    for (;;) {
      size_t dot = path.find('.', start);
      parts.push_back(path.substr(start, dot == std::string::npos ? std::string::npos : dot - start));
      if (parts.back().empty()) throw std::invalid_argument("--project '" + path + "': empty field name");
      if (dot == std::string::npos) break;
      start = dot + 1;
    }
    paths_.push_back(std::move(parts));
  }
}

bool MessageFilter::admits(std::string_view key) const {
  for (const auto& p : options_.deny)
    if (key_matches(p, key)) return false;
  if (options_.allow.empty()) return true;
  for (const auto& p : options_.allow)
    if (key_matches(p, key)) return true;
  return false;
}

namespace {

// The projected fields below one prefix, as a JSON object: paths sharing a
// first part become one nested object, in the order they were first given.
void write_object(const std::vector<std::pair<const std::vector<std::string>*, simdjson::dom::element>>& found,
                  size_t depth, std::string& out) {
  out += '{';
  std::vector<bool> done(found.size(), false);
  bool first = true;
  for (size_t i = 0; i < found.size(); ++i) {
    if (done[i]) continue;
    const std::string& name = (*found[i].first)[depth];
    if (!first) out += ',';
    first = false;
    io::append_json_string(out, name);
    out += ':';
    if (found[i].first->size() == depth + 1) {
      out += simdjson::minify(found[i].second);
      done[i] = true;
      continue;
    }
    std::vector<std::pair<const std::vector<std::string>*, simdjson::dom::element>> inner;
    for (size_t j = i; j < found.size(); ++j)
      if (!done[j] && found[j].first->size() > depth + 1 && (*found[j].first)[depth] == name) {
        inner.push_back(found[j]);
        done[j] = true;
      }
    write_object(inner, depth + 1, out);
  }
  out += '}';
}

}  // namespace

bool MessageFilter::project(std::string_view payload, std::string& out) {
  simdjson::dom::element doc;
  if (parser_.parse(payload.data(), payload.size()).get(doc) || !doc.is_object()) return false;
  std::vector<std::pair<const std::vector<std::string>*, simdjson::dom::element>> found;
  for (const auto& path : paths_) {
    simdjson::dom::element at = doc;
    bool ok = true;
    for (const auto& part : path) {
      simdjson::dom::object obj;
      if (at.get(obj) || obj.at_key(part).get(at)) {
        ok = false;
        break;
      }
    }
    if (ok) found.emplace_back(&path, at);
  }
  out.clear();
  write_object(found, 0, out);
  return true;
}

}  // namespace rvc::runtime
