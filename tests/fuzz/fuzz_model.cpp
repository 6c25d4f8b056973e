// libFuzzer target: any bytes as a model file, through the parser, the meaning checks and the
// derivation. Only momentid::Error may escape; a crash, hang or other exception is a finding.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "momentid/derive.hpp"
#include "momentid/model.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const momentid::Model model = momentid::parse_model(text, "fuzz.mom");
    const momentid::MomentSystem system = momentid::derive(model);
    (void)momentid::format_json(system);
    (void)momentid::format_latex(system);
  } catch (const momentid::Error&) {
  }
  return 0;
}

// CLN allocates a few bytes at start-up that it never frees; that is not momentid's leak.
extern "C" const char* __lsan_default_suppressions() { return "leak:libcln.so\n"; }
extern "C" const char* __lsan_default_options() { return "print_suppressions=0"; }
