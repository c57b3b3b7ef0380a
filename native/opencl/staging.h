// SPDX-License-Identifier: GPL-3.0-or-later
// Transfers to and from a GPU through page-locked ("pinned") host memory. A GPU's DMA engine reads
// pinned memory directly; from ordinary (pageable) memory the driver first copies through
// a small buffer of its own, on the calling thread. Measured on an H100 with NVIDIA's OpenCL,
// 128 MB: pageable 16.5-18.7 ms (8 GB/s); into pinned memory on 16 threads
// 2.7-3.4 ms, then its DMA 2.6 ms (50 GB/s). Pinning is slow (80 ms for 128 MB), so a
// device keeps two chunks for the life of the process and an upload goes through them in
// turn: the host threads fill one while the other's DMA runs. Downloads the other way round:
// the host threads empty one chunk while the DMA fills the other (6 MB of values read into a
// fresh array: 0.5-3.9 ms pageable, the page faults of the new array on one thread).
#pragma once

#include <algorithm>
#include <cstddef>

#include "cl_api.h"

namespace sdf::cl {

class Staging {
 public:
  Staging() = default;
  Staging(const Staging&) = delete;
  Staging& operator=(const Staging&) = delete;
  // Releases nothing: like the device's context and queue, the chunks live as long as the
  // process (OpenCL calls from static destructors can find the driver already unloaded).

  // Writes `bytes` from `data` into `destination` (from offset 0) through the chunks, and
  // returns once `data` may change (the DMA of the last chunk may still run: the queue's
  // later commands wait for it). Returns false, having written nothing, when pinned memory
  // cannot be had: the caller then writes directly. Throws Error when an OpenCL call fails.
  // threads: the host threads that copy (0: every core; at most 8 either way).
  bool write(cl_context context, cl_command_queue queue, cl_mem destination, const void* data,
             std::size_t bytes, unsigned threads);

  // Reads `bytes` of `source` (from offset 0) into `data` through the chunks; returns once
  // they are there. Returns false, having read nothing, when pinned memory cannot be had.
  // Throws Error when an OpenCL call fails. threads: as for write().
  bool read(cl_context context, cl_command_queue queue, cl_mem source, void* data,
            std::size_t bytes, unsigned threads);

  // Whether a transfer of `bytes` is worth staging: it costs a copy, and below 1 MiB (or one
  // chunk, if smaller) a direct write is as fast.
  bool worth(std::size_t bytes) const {
    return bytes >= std::min(std::size_t{1} << 20, chunk_bytes_);
  }

  // Chunks of `bytes` instead of 16 MiB, before the first write: a test override
  // (util/test_overrides.h) stages every upload on any device through tiny chunks.
  void set_chunk_bytes(std::size_t bytes) { chunk_bytes_ = bytes; }

 private:
  bool ready(cl_context context, cl_command_queue queue);
  void wait(int slot);

  // Two chunks of 16 MiB: each chunk's copy (about 0.5 ms on 8 threads) and DMA (0.3 ms)
  // are long next to a command's overhead, and 32 MiB of pinned memory is little to hold.
  std::size_t chunk_bytes_ = std::size_t{16} << 20;
  bool tried_ = false;  // chunks allocated, or found impossible, once
  cl_mem chunk_[2] = {nullptr, nullptr};
  void* host_[2] = {nullptr, nullptr};
  cl_event pending_[2] = {nullptr, nullptr};  // the last DMA out of each chunk
  int next_ = 0;  // the chunk to fill next: the one whose DMA was queued longest ago
};

}  // namespace sdf::cl
