#pragma once
// Small helpers shared by the reports that run the apps as processes (net, record, device).

#include <string>

namespace microdex::bench {

// The folder of the running microdex-bench (where the apps are built beside it).
std::string SelfDir();

// The number after `"key":` in a flat JSON text (an app's --score-out); NaN when absent.
double JsonNumber(const std::string& json, const std::string& key);

// The whole text of a file ("" when it cannot be read).
std::string ReadText(const std::string& path);

}  // namespace microdex::bench
