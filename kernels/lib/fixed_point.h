/* fixed_point.h — order-independent sums on the device: values are added as 64-bit unsigned
 * fixed-point integers with atomics, so the result is exact and the same whatever order the
 * work-items run in (float atomics would be neither). The importance pass adds weights into one
 * word per triangle; the renderer adds radiance into one word per pixel and channel.
 *
 * With IDMR_INT64_ATOMICS (cl_khr_int64_base_atomics) a word is one ulong; without it, two
 * uints (low word first) added with 32-bit atomics and an explicit carry. Both give the same
 * integers (tests/test_importance_paths.c checks this). */
#ifndef IDMR_KERNEL_FIXED_POINT_H
#define IDMR_KERNEL_FIXED_POINT_H

#if IDMR_INT64_ATOMICS
#pragma OPENCL EXTENSION cl_khr_int64_base_atomics : enable
typedef ulong fixed_word;
/* Adds `units` to word `index` with one 64-bit atomic. */
inline void fixed_add(volatile global fixed_word *words, uint index, ulong units)
{
    if (units != 0ul)
        atom_add(words + index, units);
}
#else
typedef uint fixed_word;
/* Adds `units` to word `index`: the low and high halves with 32-bit atomics, the carry of the
 * low half added to the high one. Integer addition commutes, so the sum is exact. */
inline void fixed_add(volatile global fixed_word *words, uint index, ulong units)
{
    uint low = (uint)units, high = (uint)(units >> 32);
    volatile global uint *word = words + 2 * index;
    if (low != 0u) {
        uint before = atomic_add(word, low);
        if (before + low < before)
            high += 1u;
    }
    if (high != 0u)
        atomic_add(word + 1, high);
}
#endif

#endif
