// Times `derive` on a chain of N coupled Duffing oscillators (2N states) with all multipliers up
// to degree 2, against the single Duffing oscillator at the same degree in the same run.
//
// Usage: bench_derive [N=10] [repetitions=5]

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "momentid/derive.hpp"
#include "momentid/model.hpp"
#include "timing.hpp"
#include "usage.hpp"

namespace {

// Mass i has damping c_i, stiffness k_i, cubic stiffness eps_i, and a coupling spring kc_i to
// mass i + 1; the input drives the last mass.
std::string chain_model(int n) {
  std::string text = "model chain\nstate ";
  for (int i = 1; i <= n; ++i)
    text += (i > 1 ? ", " : "") + std::string("y") + std::to_string(i) + ", v" + std::to_string(i);
  text += "\ninput x\nparam ";
  for (int i = 1; i <= n; ++i) {
    const std::string s = std::to_string(i);
    text += (i > 1 ? ", " : "") + std::string("c") + s + ", k" + s + ", eps" + s;
    if (i < n) text += ", kc" + s;
  }
  text += "\n";
  for (int i = 1; i <= n; ++i) {
    const std::string s = std::to_string(i);
    text += "y" + s + "' = v" + s + "\n";
    text +=
        "v" + s + "' = -c" + s + "*v" + s + " - k" + s + "*y" + s + " - eps" + s + "*y" + s + "^3";
    if (i < n) text += " - kc" + s + "*(y" + s + " - y" + std::to_string(i + 1) + ")";
    if (i > 1) {
      const std::string p = std::to_string(i - 1);
      text += " - kc" + p + "*(y" + s + " - y" + p + ")";
    }
    if (i == n) text += " + x";
    text += "\n";
  }
  return text;
}

struct Timing {
  double seconds = 0;
  momentid::MomentSystem system;
};

Timing time_derive(const std::string& text, int repetitions) {
  Timing out;
  out.seconds = median_seconds(repetitions, [&] {
    const momentid::Model model = momentid::parse_model(text, "chain.mom");
    out.system = momentid::derive(model, {.multipliers = {}, .degree = 2});
    out.system.model = nullptr;
  });
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (asked_for_help(argc, argv, "usage: bench_derive [N=10] [repetitions=5]")) return 0;
  const int n = argc > 1 ? std::atoi(argv[1]) : 10;
  const int repetitions = argc > 2 ? std::atoi(argv[2]) : 5;
  const Timing single = time_derive(chain_model(1), repetitions);
  const Timing chain = time_derive(chain_model(n), repetitions);
  std::printf("derive --degree 2, median of %d runs\n", repetitions);
  std::printf("  1 oscillator  (2 states):  %9.4f s  %5zu equations\n", single.seconds,
              single.system.equations.size());
  std::printf(
      "  %d oscillators (%d states): %9.4f s  %5zu equations, %zu moments, rank %d, "
      "%zu skipped\n",
      n, 2 * n, chain.seconds, chain.system.equations.size(), chain.system.moments.size(),
      chain.system.generic_rank, chain.system.skipped.size());
  std::printf("  ratio chain / single: %.1f\n", chain.seconds / single.seconds);
  return 0;
}
