// SPDX-License-Identifier: GPL-3.0-or-later
#include "staging.h"

#include <algorithm>
#include <cstring>

#include "util/parallel.h"

namespace sdf::cl {

namespace {

// Threads that copy into a chunk, at most: memory-bound, so more than 8 only contend (16
// threads were slower than 4 in the H100 measurement above).
constexpr unsigned kCopyThreads = 8;
constexpr std::size_t kCopyGrain = std::size_t{1} << 20;

// Copies between a chunk and the caller's memory on up to `threads` (0: every core) threads.
void copy(void* to, const void* from, std::size_t bytes, unsigned threads) {
  parallel_for(bytes, kCopyGrain, std::min(kCopyThreads, resolve_threads(threads)),
               [&](std::size_t begin, std::size_t end) {
                 std::memcpy(static_cast<char*>(to) + begin, static_cast<const char*>(from) + begin,
                             end - begin);
               });
}

}  // namespace

bool Staging::ready(cl_context context, cl_command_queue queue) {
  if (tried_) return host_[1] != nullptr;
  tried_ = true;
  const Api& cl = *api();
  for (int k = 0; k < 2; ++k) {
    cl_int err = CL_SUCCESS;
    chunk_[k] = cl.clCreateBuffer(context, CL_MEM_ALLOC_HOST_PTR | CL_MEM_READ_ONLY, chunk_bytes_,
                                  nullptr, &err);
    if (err != CL_SUCCESS) break;
    host_[k] = cl.clEnqueueMapBuffer(queue, chunk_[k], CL_TRUE, CL_MAP_WRITE, 0, chunk_bytes_, 0,
                                     nullptr, nullptr, &err);
    if (err != CL_SUCCESS) {
      host_[k] = nullptr;
      break;
    }
  }
  return host_[1] != nullptr;  // a lone first chunk stays unused
}

void Staging::wait(int slot) {
  if (!pending_[slot]) return;
  const Api& cl = *api();
  const cl_int err = cl.clWaitForEvents(1, &pending_[slot]);
  cl.clReleaseEvent(pending_[slot]);
  pending_[slot] = nullptr;
  check(err, "clWaitForEvents (staging)");
}

bool Staging::write(cl_context context, cl_command_queue queue, cl_mem destination,
                    const void* data, std::size_t bytes, unsigned threads) {
  if (!ready(context, queue)) return false;
  const Api& cl = *api();
  const char* from = static_cast<const char*>(data);
  for (std::size_t offset = 0; offset < bytes; offset += chunk_bytes_, next_ ^= 1) {
    const int slot = next_;
    const std::size_t size = std::min(chunk_bytes_, bytes - offset);
    wait(slot);  // its last DMA must be done before the chunk is overwritten
    copy(host_[slot], from + offset, size, threads);
    check(cl.clEnqueueWriteBuffer(queue, destination, CL_FALSE, offset, size, host_[slot], 0,
                                  nullptr, &pending_[slot]),
          "clEnqueueWriteBuffer (staged)");
  }
  return true;
}

bool Staging::read(cl_context context, cl_command_queue queue, cl_mem source, void* data,
                   std::size_t bytes, unsigned threads) {
  if (!ready(context, queue)) return false;
  const Api& cl = *api();
  char* to = static_cast<char*>(data);
  auto queue_read = [&](std::size_t offset, int slot) {
    wait(slot);  // an upload's DMA out of the chunk must be done before it is overwritten
    check(cl.clEnqueueReadBuffer(queue, source, CL_FALSE, offset,
                                 std::min(chunk_bytes_, bytes - offset), host_[slot], 0, nullptr,
                                 &pending_[slot]),
          "clEnqueueReadBuffer (staged)");
  };
  int slot = next_;
  queue_read(0, slot);
  for (std::size_t offset = 0; offset < bytes; offset += chunk_bytes_, slot ^= 1) {
    if (offset + chunk_bytes_ < bytes) queue_read(offset + chunk_bytes_, slot ^ 1);
    wait(slot);
    copy(to + offset, host_[slot], std::min(chunk_bytes_, bytes - offset), threads);
  }
  next_ = slot;
  return true;
}

}  // namespace sdf::cl
