// JSON read with each object's keys unique. nlohmann keeps the last of a repeated key, so a
// capture header with rate_hz twice was analysed at its second rate without a word, and a
// passport with "outcome" twice drawn with its last (a review); RFC 8259 leaves such a text's
// meaning open, and the rig never writes one.
#pragma once
#include <istream>
#include <iterator>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace rig {

struct RepeatedJsonKey : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// Parses `text` as nlohmann::json::parse does (its parse_error and out_of_range included);
// RepeatedJsonKey ("key 'rate_hz' appears twice in one object") where an object repeats a key.
template <class Json = nlohmann::json>
Json parse_json_unique_keys(std::string_view text) {
  std::vector<std::set<std::string>> open;  // the keys of each object being read, innermost last
  std::string repeated;
  const auto seen = [&](int, typename Json::parse_event_t ev, Json& parsed) {
    using E = typename Json::parse_event_t;
    if (ev == E::object_start) open.emplace_back();
    else if (ev == E::object_end && !open.empty()) open.pop_back();
    else if (ev == E::key && !open.empty() && !open.back().insert(parsed.template get<std::string>()).second &&
             repeated.empty())
      repeated = parsed.template get<std::string>();
    return true;
  };
  Json j = Json::parse(text, seen);
  if (!repeated.empty()) throw RepeatedJsonKey("key '" + repeated + "' appears twice in one object");
  return j;
}

// The same from a stream, read whole (a checkpoint, run.json, a seal: a key twice in one is refused,
// not read at its last).
template <class Json = nlohmann::json>
Json parse_json_unique_keys(std::istream& in) {
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  return parse_json_unique_keys<Json>(text);
}

}  // namespace rig
