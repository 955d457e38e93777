// The translation unit that compiles a precompiled header set (cmake/alight.cmake, ALIGHT_PCH).
