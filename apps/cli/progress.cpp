// SPDX-License-Identifier: Apache-2.0
#include "progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace ubersim::cli {

ProgressLine::ProgressLine(bool shown) : shown_(shown), tty_(isatty(STDERR_FILENO) != 0) {}

ProgressLine::~ProgressLine() { Clear(); }

void ProgressLine::Redraw(const std::string& text) {
  if (!shown_ || !tty_) return;
  std::fprintf(stderr, "\r%s\033[K", text.c_str());
  std::fflush(stderr);
  drawn_ = true;
}

void ProgressLine::Write(const std::string& text) {
  if (!shown_) return;
  std::fprintf(stderr, "%s%s\n", tty_ ? "\r" : "", text.c_str());
  std::fflush(stderr);
  drawn_ = false;
}

void ProgressLine::Clear() {
  if (!drawn_) return;
  std::fprintf(stderr, "\r\033[K");
  std::fflush(stderr);
  drawn_ = false;
}

std::string Bar(double fraction, int width) {
  const int filled = std::clamp(static_cast<int>(fraction * width), 0, width);
  std::string bar(static_cast<std::size_t>(width) + 2, ' ');
  bar.front() = '[';
  std::fill_n(bar.begin() + 1, filled, '#');
  bar.back() = ']';
  return bar;
}

}  // namespace ubersim::cli
