// The host of a precompiled header (cmake/precompiled_headers.cmake): compiling it builds the
// header set that the other targets reuse. It holds no code of its own.
