// SPDX-License-Identifier: Apache-2.0
#pragma once

/// Marks a symbol of libubersim_sdk that plugins and the kernel link against.
#if defined(UBERSIM_SDK_BUILDING)
#define UBERSIM_SDK_API __attribute__((visibility("default")))
#else
#define UBERSIM_SDK_API __attribute__((visibility("default")))
#endif
