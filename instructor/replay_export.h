#pragma once
// Exports of a recorded session: one CSV file per topic, and a Markdown summary (per station:
// trainee, scene, seed, steps, the final score with its terms, cues and task events).

#include <string>

#include "common/record/session_reader.h"

namespace microdex::instructor {

// Writes DIR/<topic>.csv (DIR is created). Returns the number of rows written; throws
// std::runtime_error "DIR/FILE: reason" when a file cannot be written.
std::size_t ExportCsv(record::SessionReader& reader, const std::string& dir);

// The session summary in Markdown.
std::string SessionSummaryMarkdown(record::SessionReader& reader);

}  // namespace microdex::instructor
