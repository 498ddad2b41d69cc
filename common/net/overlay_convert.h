#pragma once
// The CueOverlay topic (idl/cue_overlay.idl) to and from common/cues/cue_overlay.h.

#include <string>

#include "common/cues/cue_overlay.h"
#include "common/net/convert.h"
#include "common/net/messages.h"
#include "cue_overlay.h"

namespace microdex::net {

// The overlay and the header of the step it shows; active: the cues on (bit (1 << CueKind)).
void ToMsg(const Header& header, std::uint32_t active, const cues::CueOverlay& in,
           msg::CueOverlay& out);
// False (and `why`: "field: reason") for a sample out of its bounds: a non-finite point or
// colour, a role that names none, a point count that is not a multiple of 3.
bool FromMsg(const msg::CueOverlay& in, Header& header, std::uint32_t& active,
             cues::CueOverlay& out, std::string* why = nullptr);

}  // namespace microdex::net
