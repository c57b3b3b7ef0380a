// SPDX-License-Identifier: GPL-3.0-or-later
// Pageable against pinned uploads to the first OpenCL GPU: what native/opencl/staging.h is
// built on. 128 MB written from ordinary memory, from pinned memory (after a copy into it on
// 16 threads), and through two pinned 8 MB chunks in turn. Standalone (links libOpenCL):
//   gcc -O2 -o /tmp/pinned_upload bench/pinned_upload.c -lOpenCL -lpthread && /tmp/pinned_upload
#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <pthread.h>
static double now(void) { struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t); return t.tv_sec + t.tv_nsec * 1e-9; }
#define CHECK(x) do { cl_int e_ = (x); if (e_ != CL_SUCCESS) { printf("error %d at %d\n", e_, __LINE__); exit(1); } } while (0)
struct CopyJob { char* dst; const char* src; size_t n; };
static void* copy_part(void* p) { struct CopyJob* j = p; memcpy(j->dst, j->src, j->n); return NULL; }
static void parallel_copy(char* dst, const char* src, size_t n, int threads) {
  pthread_t t[64]; struct CopyJob j[64];
  for (int i = 0; i < threads; ++i) { size_t a = n * i / threads, b = n * (i + 1) / threads; j[i] = (struct CopyJob){dst + a, src + a, b - a}; pthread_create(&t[i], 0, copy_part, &j[i]); }
  for (int i = 0; i < threads; ++i) pthread_join(t[i], 0);
}
int main(void) {
  cl_platform_id plats[8]; cl_uint np; CHECK(clGetPlatformIDs(8, plats, &np));
  cl_device_id dev = 0; char name[256];
  for (cl_uint p = 0; p < np && !dev; ++p) { cl_device_id ds[8]; cl_uint nd; if (clGetDeviceIDs(plats[p], CL_DEVICE_TYPE_GPU, 8, ds, &nd) == CL_SUCCESS && nd) { dev = ds[0]; } }
  if (!dev) { printf("no OpenCL GPU\n"); return 1; }
  clGetDeviceInfo(dev, CL_DEVICE_NAME, sizeof name, name, 0); printf("device %s\n", name);
  cl_int err; cl_context ctx = clCreateContext(0, 1, &dev, 0, 0, &err); CHECK(err);
  cl_command_queue q = clCreateCommandQueue(ctx, dev, 0, &err); CHECK(err);
  const size_t total = (size_t)128 << 20;
  char* src = malloc(total); for (size_t i = 0; i < total; i += 4096) src[i] = (char)i; memset(src, 1, total);
  cl_mem dbuf = clCreateBuffer(ctx, CL_MEM_READ_WRITE, total, 0, &err); CHECK(err);
  for (int r = 0; r < 4; ++r) { double t0 = now(); CHECK(clEnqueueWriteBuffer(q, dbuf, CL_TRUE, 0, total, src, 0, 0, 0)); double t = now() - t0; printf("pageable blocking write 128 MB: %.2f ms (%.1f GB/s)\n", t * 1e3, total / t / 1e9); }
  for (int r = 0; r < 2; ++r) { double t0 = now(); for (size_t off = 0; off < total; off += 16 << 20) CHECK(clEnqueueWriteBuffer(q, dbuf, CL_FALSE, off, 16 << 20, src + off, 0, 0, 0)); CHECK(clFinish(q)); double t = now() - t0; printf("pageable nonblocking 8 x 16 MB: %.2f ms\n", t * 1e3); }
  // Pinned staging: whole size
  double t0 = now();
  cl_mem pin = clCreateBuffer(ctx, CL_MEM_ALLOC_HOST_PTR | CL_MEM_READ_ONLY, total, 0, &err); CHECK(err);
  char* hp = clEnqueueMapBuffer(q, pin, CL_TRUE, CL_MAP_WRITE, 0, total, 0, 0, 0, &err); CHECK(err);
  printf("pinned 128 MB create+map: %.2f ms\n", (now() - t0) * 1e3);
  for (int r = 0; r < 3; ++r) { t0 = now(); parallel_copy(hp, src, total, 16); double c = now() - t0; CHECK(clEnqueueWriteBuffer(q, dbuf, CL_TRUE, 0, total, hp, 0, 0, 0)); double t = now() - t0; printf("pinned: copy in (16 threads) %.2f ms, + write = %.2f ms (write %.1f GB/s)\n", c * 1e3, t * 1e3, total / (t - c) / 1e9); }
  for (int r = 0; r < 2; ++r) { t0 = now(); memcpy(hp, src, total); double c = now() - t0; printf("pinned copy in, 1 thread: %.2f ms\n", c * 1e3); }
  // Chunked double buffering through 2 x 8 MB pinned chunks
  const size_t chunk = 8 << 20;
  cl_mem st[2]; char* sp[2]; cl_event ev[2] = {0, 0};
  t0 = now();
  for (int i = 0; i < 2; ++i) { st[i] = clCreateBuffer(ctx, CL_MEM_ALLOC_HOST_PTR | CL_MEM_READ_ONLY, chunk, 0, &err); CHECK(err); sp[i] = clEnqueueMapBuffer(q, st[i], CL_TRUE, CL_MAP_WRITE, 0, chunk, 0, 0, 0, &err); CHECK(err); }
  printf("2 x 8 MB pinned create+map: %.2f ms\n", (now() - t0) * 1e3);
  for (int threads = 1; threads <= 16; threads *= 4)
  for (int r = 0; r < 3; ++r) {
    t0 = now();
    int k = 0;
    for (size_t off = 0; off < total; off += chunk, k ^= 1) {
      if (ev[k]) { CHECK(clWaitForEvents(1, &ev[k])); clReleaseEvent(ev[k]); ev[k] = 0; }
      parallel_copy(sp[k], src + off, chunk, threads);
      CHECK(clEnqueueWriteBuffer(q, dbuf, CL_FALSE, off, chunk, sp[k], 0, 0, &ev[k]));
    }
    CHECK(clFinish(q)); for (int i = 0; i < 2; ++i) if (ev[i]) { clReleaseEvent(ev[i]); ev[i] = 0; }
    double t = now() - t0; printf("double-buffered 2 x 8 MB, %d copy threads: %.2f ms (%.1f GB/s)\n", threads, t * 1e3, total / t / 1e9);
  }
  return 0;
}
