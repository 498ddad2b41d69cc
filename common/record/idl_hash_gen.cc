// Build-time tool: writes a header with the XXH3-64 hash of each IDL file's text, so that a
// recording names the exact type definitions its CDR bytes follow.
//   microdex-idl-hash OUT.h FILE.idl...

#include <xxhash.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: microdex-idl-hash OUT.h FILE.idl...\n");
    return 2;
  }
  std::ostringstream out;
  out << "#pragma once\n// Generated at build time from idl/*.idl: XXH3-64 of each file's text.\n"
      << "#include <cstdint>\n\nnamespace microdex::record {\n\n"
      << "struct IdlFileHash {\n  const char* stem;\n  std::uint64_t xxh3;\n};\n\n"
      << "inline constexpr IdlFileHash kIdlFileHashes[] = {\n";
  for (int i = 2; i < argc; ++i) {
    std::ifstream f(argv[i], std::ios::binary);
    if (!f) {
      std::fprintf(stderr, "microdex-idl-hash: %s: cannot read\n", argv[i]);
      return 2;
    }
    const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    std::string stem = argv[i];
    if (const auto slash = stem.rfind('/'); slash != std::string::npos) stem.erase(0, slash + 1);
    if (const auto dot = stem.rfind('.'); dot != std::string::npos) stem.erase(dot);
    char hex[32];
    std::snprintf(hex, sizeof hex, "0x%016llxULL",
                  static_cast<unsigned long long>(XXH3_64bits(text.data(), text.size())));
    out << "    {\"" << stem << "\", " << hex << "},\n";
  }
  out << "};\n\n}  // namespace microdex::record\n";
  // Rewritten only when it changes, so that dependents are not rebuilt for nothing.
  std::ifstream old(argv[1], std::ios::binary);
  const std::string previous((std::istreambuf_iterator<char>(old)),
                             std::istreambuf_iterator<char>());
  if (previous == out.str()) return 0;
  std::ofstream o(argv[1], std::ios::binary | std::ios::trunc);
  o << out.str();
  return o ? 0 : 2;
}
