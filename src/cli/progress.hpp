#pragma once
// Progress of a long pass over the data, on standard error when it is a terminal.

#include <chrono>
#include <cstddef>
#include <functional>
#include <optional>

namespace momentid::cli {

// Shows rows read, the rate, the share done and the time left, updated four times a second, on
// one line of standard error that is cleared at the end. Shows nothing when not `wanted` or
// when standard error is not a terminal (redirected output never carries it).
class TerminalProgress {
 public:
  explicit TerminalProgress(bool wanted);
  ~TerminalProgress();
  TerminalProgress(const TerminalProgress&) = delete;
  TerminalProgress& operator=(const TerminalProgress&) = delete;

  // For IdentifyOptions::progress and CheckOptions::progress: empty when nothing is shown.
  std::function<void(std::size_t rows, std::optional<double> fraction)> callback();
  // Clears the line, before the results are printed (the destructor does so on errors).
  void finish();

 private:
  void update(std::size_t rows, std::optional<double> fraction);

  using Clock = std::chrono::steady_clock;
  bool shown_ = false, drawn_ = false;
  Clock::time_point start_, next_;
  std::size_t last_rows_ = 0;
};

}  // namespace momentid::cli
