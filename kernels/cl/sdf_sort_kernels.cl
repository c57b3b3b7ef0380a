/* SPDX-License-Identifier: GPL-3.0-or-later */
/* A stable radix sort of (key, value) pairs on the device, 4 bits a pass (Satish, Harris and
 * Garland 2009): per tile of SDF_SORT_GROUP items, count each digit; scan the counts, digit
 * major, into every tile's first place for each digit; sort each tile locally by the digit
 * (four stable one-bit splits) and write each item to its digit's place. Stable, so passes
 * from the lowest digit up sort by the whole key, ties in input order. Used for the faces'
 * Morton order of the device-built tree (sdf_lbvh_kernels.cl). */

#define SDF_SORT_GROUP 256
#define SDF_SORT_DIGITS 16

static inline uint sdf_sort_digit(uint key, int shift) { return (key >> shift) & 15u; }

/* counts[digit * tiles + tile]: how many of tile's keys have the digit. */
__kernel __attribute__((reqd_work_group_size(SDF_SORT_GROUP, 1, 1)))
void sdf_sort_count(__global const uint* restrict keys, uint n, int shift,
                    __global uint* restrict counts) {
  __local uint histogram[SDF_SORT_DIGITS];
  uint lid = get_local_id(0), gid = get_global_id(0);
  if (lid < SDF_SORT_DIGITS) histogram[lid] = 0;
  barrier(CLK_LOCAL_MEM_FENCE);
  if (gid < n) atomic_inc(&histogram[sdf_sort_digit(keys[gid], shift)]);
  barrier(CLK_LOCAL_MEM_FENCE);
  if (lid < SDF_SORT_DIGITS) counts[lid * get_num_groups(0) + get_group_id(0)] = histogram[lid];
}

/* The exclusive prefix sum of x over the work group (SDF_SORT_GROUP items), and the total. */
static inline uint sdf_group_exclusive_scan(__local uint* scratch, uint lid, uint x,
                                            uint* total) {
  scratch[lid] = x;
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint offset = 1; offset < SDF_SORT_GROUP; offset <<= 1) {
    uint y = lid >= offset ? scratch[lid - offset] : 0;
    barrier(CLK_LOCAL_MEM_FENCE);
    scratch[lid] += y;
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  uint inclusive = scratch[lid];
  *total = scratch[SDF_SORT_GROUP - 1];
  barrier(CLK_LOCAL_MEM_FENCE);
  return inclusive - x;
}

/* One work group: counts (count entries) become their exclusive prefix sum. */
__kernel __attribute__((reqd_work_group_size(SDF_SORT_GROUP, 1, 1)))
void sdf_sort_scan(__global uint* counts, uint count) {
  __local uint scratch[SDF_SORT_GROUP];
  uint lid = get_local_id(0);
  uint per_item = (count + SDF_SORT_GROUP - 1) / SDF_SORT_GROUP;
  uint begin = min(count, lid * per_item), end = min(count, begin + per_item);
  uint sum = 0;
  for (uint i = begin; i < end; ++i) sum += counts[i];
  uint total;
  uint running = sdf_group_exclusive_scan(scratch, lid, sum, &total);
  for (uint i = begin; i < end; ++i) {
    uint c = counts[i];
    counts[i] = running;
    running += c;
  }
}

/* Each tile sorted locally by the digit, then every item written to its digit's place:
 * places (scanned counts) + its rank among the tile's items of that digit. Items past n
 * take the last digit, so they sort to the tile's end, and are not written. */
__kernel __attribute__((reqd_work_group_size(SDF_SORT_GROUP, 1, 1)))
void sdf_sort_scatter(__global const uint* restrict keys_in,
                      __global const uint* restrict values_in, uint n, int shift,
                      __global const uint* restrict places, __global uint* restrict keys_out,
                      __global uint* restrict values_out) {
  __local uint scratch[SDF_SORT_GROUP];
  __local uint first_of_digit[SDF_SORT_DIGITS];
  uint lid = get_local_id(0), gid = get_global_id(0);
  uint key = gid < n ? keys_in[gid] : 0xffffffffu;
  uint value = gid < n ? values_in[gid] : 0u;
  uint digit = gid < n ? sdf_sort_digit(key, shift) : SDF_SORT_DIGITS - 1;
  uint position = lid;
  for (int bit = 0; bit < 4; ++bit) {
    uint one = (digit >> bit) & 1u;
    uint zeros;
    uint zeros_before = sdf_group_exclusive_scan(scratch, position, 1u - one, &zeros);
    /* scanned in current order: item at `position` has zeros_before zeros ahead of it */
    position = one ? zeros + (position - zeros_before) : zeros_before;
  }
  scratch[position] = digit;
  barrier(CLK_LOCAL_MEM_FENCE);
  /* Where each digit starts in the sorted tile. */
  if (position == 0 || scratch[position - 1] != digit) first_of_digit[digit] = position;
  barrier(CLK_LOCAL_MEM_FENCE);
  if (gid < n) {
    uint tile = get_group_id(0);
    uint place = places[digit * get_num_groups(0) + tile] + (position - first_of_digit[digit]);
    keys_out[place] = key;
    values_out[place] = value;
  }
}
