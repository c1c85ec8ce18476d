// <windows.h> as the platform files include it: without the rarely used APIs, and without the
// min/max macros that would break std::min and std::max. Windows only.
#pragma once

#ifndef WIN32_LEAN_AND_MEAN
#define WIN32_LEAN_AND_MEAN
#endif
#ifndef NOMINMAX
#define NOMINMAX
#endif
#include <windows.h>
