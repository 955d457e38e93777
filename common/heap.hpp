#pragma once
// Heap settings for processes that handle a frame at a time.

namespace alight {

/// Makes glibc keep freed memory for reuse instead of giving it back to the kernel: blocks up to
/// 32 MiB come from the heap rather than from their own mmap, and the heap's top is trimmed only
/// past 512 MiB free. By default every buffer above 128 KiB (an image, an integral image, a
/// response map) is mapped on allocation and unmapped on release, so each frame page-faults all
/// of them in again; on this project's virtual machines a fault costs several microseconds and
/// STAR detection took 12.8 ms per 640x480 frame instead of 1.4 ms (bench/vision). What real-time
/// guides do (ROS 2 real-time, rttest: no trimming, no mmap), short of locking memory, which
/// needs a privilege a node should not ask for. Returns false if glibc refused a setting (the
/// process runs as before, only slower).
bool retain_freed_memory();

}  // namespace alight
