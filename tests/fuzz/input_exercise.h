#pragma once
// What the fuzz targets and their corpus tests do with one input (scene_loader_fuzz.cc,
// sample_validator_fuzz.cc, ws_message_fuzz.cc): hand it to the code that receives such input
// from outside. Must never crash, hang or leak, whatever the bytes; a rejection is an
// exception the receiving code catches (scene) or a false / an error reply (samples, pages).

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace microdex::fuzz {

// The bytes as a scene file's YAML text (scene::ParseScene). True when it loaded.
bool ExerciseSceneText(std::string_view text);

// A received DDS sample: byte 0 picks the topic type (modulo kSampleTypes), the rest is the
// serialized payload (CDR with its encapsulation header) as a reader gets it. Deserialized by
// the generated type support, then validated by the receiving side's check (net::FromMsg; a
// cue command also by cues::CheckCue, as the station does).
constexpr std::size_t kSampleTypes = 11;
struct SampleResult {
  bool deserialized = false;
  bool valid = false;
};
SampleResult ExerciseSample(const std::uint8_t* data, std::size_t size);
// One valid sample of every type, in the format above, named by type (the seed corpus).
std::vector<std::pair<std::string, std::vector<std::uint8_t>>> ValidSamples();

// A WebSocket text message from a page, to every decoder of one: the station page's input
// (ParsePageInput), the console's cue command (ParseConsoleMessage) and session command
// (ParseSessionMessage), the frame credit (view::ParseCredit). How many accepted it.
int ExerciseWsMessage(const std::string& text);

}  // namespace microdex::fuzz
