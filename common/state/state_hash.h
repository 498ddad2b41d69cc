#pragma once
// The state hash: a stable digest of a StationState, to compare two runs step by step (two
// stations, a recording and its re-simulation) without shipping the state.
//
// Definition (version kStateHashVersion): XXH3-64 (xxHash, seed 0) of the byte stream made of
// the version as a little-endian uint32, then every field of VisitStationState in its order,
// each scalar as its little-endian bytes (bool as one byte 0/1; enums as their underlying
// integer; doubles and floats as their IEEE-754 bits, so NaN payloads and −0.0 count). Field
// names are not hashed; counted arrays contribute their count, then their elements; an
// optional module section contributes a presence byte, then its fields. The digest is the
// same on every little-endian platform for the same build's state layout; a change to the
// field list bumps kStateHashVersion.
//
// Cost: one pass over the state (the tissue's grid field dominates); no allocation, no lock,
// so the haptic thread may take it inside a tick.

#include <cstdint>

#include "common/state/station_state.h"

namespace microdex::state {

inline constexpr std::uint32_t kStateHashVersion = 11;

std::uint64_t CalcStateHash(const StationState& state);

}  // namespace microdex::state
