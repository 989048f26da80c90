// SPDX-License-Identifier: Apache-2.0
// The source that carries the tests' precompiled headers (tests/CMakeLists.txt,
// ubersim_test_pch): the headers come from the build; this file only needs a translation unit.
