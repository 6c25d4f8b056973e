#include "cli/progress.hpp"

#include <unistd.h>

#include <cstdio>

namespace momentid::cli {
namespace {

constexpr auto kInterval = std::chrono::milliseconds(250);

}  // namespace

TerminalProgress::TerminalProgress(bool wanted) : shown_(wanted && isatty(STDERR_FILENO) == 1) {}

TerminalProgress::~TerminalProgress() { finish(); }

void TerminalProgress::finish() {
  if (drawn_) std::fputs("\r\033[K", stderr);
  drawn_ = false;
}

std::function<void(std::size_t, std::optional<double>)> TerminalProgress::callback() {
  if (!shown_) return {};
  return [this](std::size_t rows, std::optional<double> fraction) { update(rows, fraction); };
}

void TerminalProgress::update(std::size_t rows, std::optional<double> fraction) {
  const Clock::time_point now = Clock::now();
  if (rows < last_rows_ || last_rows_ == 0) {  // a pass begins (identify may make two)
    start_ = now;
    next_ = now + kInterval;
  }
  last_rows_ = rows;
  if (now < next_) return;
  next_ = now + kInterval;
  const double seconds = std::chrono::duration<double>(now - start_).count();
  std::fprintf(stderr, "\r  read %.3g rows, %.3g rows/s", static_cast<double>(rows),
               static_cast<double>(rows) / seconds);
  if (fraction && *fraction > 0) {
    std::fprintf(stderr, ", %.0f%%", 100 * *fraction);
    const double left = seconds * (1 - *fraction) / *fraction;
    if (left >= 1) std::fprintf(stderr, ", about %.0f s left", left);
  }
  std::fputs("\033[K", stderr);
  std::fflush(stderr);
  drawn_ = true;
}

}  // namespace momentid::cli
