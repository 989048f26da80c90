// SPDX-License-Identifier: Apache-2.0
// An ordinary shared library that happens to carry a plugin's file name.
extern "C" __attribute__((visibility("default"))) int fake_plain_answer() { return 42; }
