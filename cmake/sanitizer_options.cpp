// SPDX-License-Identifier: Apache-2.0
// Defaults of the sanitizer runtimes for every executable of a UBERSIM_SANITIZE build (the
// runtimes call these at start-up). ASAN_OPTIONS, UBSAN_OPTIONS and LSAN_OPTIONS in the
// environment still override each setting.

extern "C" {

// Also report a dynamic initialiser that reads a global of another file before that is set up.
const char* __asan_default_options() { return "check_initialization_order=1"; }

// Say where: without a stack, an UBSan report names only the line of the check.
const char* __ubsan_default_options() { return "print_stacktrace=1"; }

}  // extern "C"
