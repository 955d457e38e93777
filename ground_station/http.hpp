#pragma once
// cpp-httplib (Debian libcpp-httplib-dev). Its header pulls in <resolv.h>, whose `_res` macro
// (the resolver's per-thread state) breaks Eigen's headers when they come later; nothing here
// uses the resolver state, so the macro goes.
#include <httplib.h>
#undef _res
