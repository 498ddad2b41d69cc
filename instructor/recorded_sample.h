#pragma once
// Decoding a recorded sample (common/record) back into its generated DDS type.

#include <fastdds/rtps/common/SerializedPayload.h>

#include <cstring>
#include <exception>
#include <span>
#include <string>

namespace microdex::instructor {

// Deserializes `cdr` with PubSubType into `out`. False (with the reason in *why) when the
// bytes are not a valid sample of the type: too short, a length beyond the bytes left, a
// bound exceeded... Fast CDR reports those by throwing; nothing escapes.
template <class PubSubType, class Msg>
bool DecodeSample(std::span<const std::uint8_t> cdr, Msg& out, std::string* why = nullptr) {
  if (cdr.size() < 4 || cdr.size() > 64u * 1024 * 1024) {
    if (why) *why = "CDR of " + std::to_string(cdr.size()) + " bytes";
    return false;
  }
  try {
    PubSubType type;
    eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<std::uint32_t>(cdr.size()));
    std::memcpy(payload.data, cdr.data(), cdr.size());
    payload.length = static_cast<std::uint32_t>(cdr.size());
    if (!type.deserialize(&payload, &out)) {
      if (why) *why = "not a valid " + std::string(type.getName());
      return false;
    }
  } catch (const std::exception& e) {
    if (why) *why = std::string("malformed CDR: ") + e.what();
    return false;
  }
  return true;
}

}  // namespace microdex::instructor
