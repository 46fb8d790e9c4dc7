#pragma once
// The one rule every part of a checkpoint follows: an object may hold only the keys this
// version of rig writes there. A checkpoint is rig's own file; a key it does not know is an
// edit or another version's, whose meaning a resume would silently drop.

#include <algorithm>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace rig {

// What a refused key is told (after its path).
inline constexpr std::string_view kNotACheckpointKey =
    "not a key of a checkpoint (edited, or written by another version of rig?)";

// The first key of `object` that is in neither `keys` nor `also` (a list shared by several
// objects, such as a recording's keys); nullopt when every key is known or `object` is not an object.
inline std::optional<std::string> first_unknown_key(const nlohmann::json& object,
                                                    std::span<const std::string_view> keys,
                                                    std::span<const std::string_view> also = {}) {
  if (!object.is_object()) return std::nullopt;
  for (const auto& [k, v] : object.items())
    if (std::find(keys.begin(), keys.end(), k) == keys.end() && std::find(also.begin(), also.end(), k) == also.end())
      return k;
  return std::nullopt;
}

}  // namespace rig
