// SPDX-License-Identifier: Apache-2.0
// The one status line of the commands that take time (run, bench, batch, soak): on stderr,
// redrawn in place when stderr is a terminal; what goes elsewhere is each command's choice.
#pragma once

#include <string>

namespace ubersim::cli {

/// One status line on stderr. Nothing is drawn when it is not shown (--quiet); Redraw draws
/// only on a terminal, Write on a terminal and elsewhere.
class ProgressLine {
 public:
  /// `shown` false: the line never prints (--quiet).
  explicit ProgressLine(bool shown = true);
  /// Removes a line still drawn (an error ended the command).
  ~ProgressLine();
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  /// True when stderr is a terminal: the line is redrawn in place.
  bool OnTerminal() const { return tty_; }
  /// On a terminal, draws `text` over the line; elsewhere nothing.
  void Redraw(const std::string& text);
  /// Writes `text` as a line of its own (on a terminal over the line, which it ends).
  void Write(const std::string& text);
  /// On a terminal, removes the line (before other output, or at the end).
  void Clear();

 private:
  bool shown_;
  bool tty_;
  bool drawn_ = false;  // a redrawn line is on the terminal
};

/// A bar of `width` characters filled to `fraction` (0..1): "[#####     ]".
std::string Bar(double fraction, int width = 30);

}  // namespace ubersim::cli
