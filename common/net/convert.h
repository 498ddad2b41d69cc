#pragma once
// Conversions between the generated DDS types (microdex::msg) and the plain structs of
// messages.h. ToMsg never fails for a value within the IDL bounds (it is a programming error
// otherwise: MICRODEX_CHECK). FromMsg validates a received sample: strings and sequences
// within their IDL bounds, enums in range, every number finite; it returns false (and leaves
// a one-line reason in *why when given) for a sample to be dropped.

#include <string>

#include "common/net/messages.h"
#include "cue_command.h"
#include "device_input.h"
#include "needle_state.h"
#include "score.h"
#include "station_info.h"
#include "task_event.h"
#include "telemetry.h"
#include "thread_state.h"
#include "tissue_state.h"
#include "tool_state.h"

namespace microdex::net {

// A mask of active cues (bit 1 << cues::CueKind) as on the wire (bit 1 << msg::CueKind of the
// same name), and back (false for a bit that names no kind).
std::uint32_t ActiveCuesToWire(std::uint32_t plain);
bool ActiveCuesFromWire(std::uint32_t bits, std::uint32_t* plain);

void ToMsg(const StationInfo& in, msg::StationInfo& out);
void ToMsg(const DeviceInput& in, msg::DeviceInput& out);
void ToMsg(const ToolState& in, msg::ToolState& out);
void ToMsg(const NeedleState& in, msg::NeedleState& out);
void ToMsg(const ThreadState& in, msg::ThreadState& out);
void ToMsg(const TissueState& in, msg::TissueState& out);
void ToMsg(const Telemetry& in, msg::Telemetry& out);
void ToMsg(const CueCommand& in, msg::CueCommand& out);
void ToMsg(const TaskEvent& in, msg::TaskEvent& out);
void ToMsg(const Score& in, msg::Score& out);

bool FromMsg(const msg::StationInfo& in, StationInfo& out, std::string* why = nullptr);
bool FromMsg(const msg::DeviceInput& in, DeviceInput& out, std::string* why = nullptr);
bool FromMsg(const msg::ToolState& in, ToolState& out, std::string* why = nullptr);
bool FromMsg(const msg::NeedleState& in, NeedleState& out, std::string* why = nullptr);
bool FromMsg(const msg::ThreadState& in, ThreadState& out, std::string* why = nullptr);
bool FromMsg(const msg::TissueState& in, TissueState& out, std::string* why = nullptr);
bool FromMsg(const msg::Telemetry& in, Telemetry& out, std::string* why = nullptr);
bool FromMsg(const msg::CueCommand& in, CueCommand& out, std::string* why = nullptr);
bool FromMsg(const msg::TaskEvent& in, TaskEvent& out, std::string* why = nullptr);
bool FromMsg(const msg::Score& in, Score& out, std::string* why = nullptr);

}  // namespace microdex::net
