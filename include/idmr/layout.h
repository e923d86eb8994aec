/* idmr/layout.h — the one compatibility shim between the host C compiler and OpenCL C.
 *
 * Every struct in include/idmr/ is read by both sides, so it may hold only 32-bit scalars
 * (float, int, unsigned int) in groups of 16 bytes, with explicit padding and no vector
 * members. IDMR_STATIC_ASSERT checks sizes and offsets on the host (C or C++); in OpenCL C it is
 * a no-op (the layout is the same by construction: no vectors, no implicit padding). */
#ifndef IDMR_LAYOUT_H
#define IDMR_LAYOUT_H

#ifdef __OPENCL_VERSION__
#define IDMR_STATIC_ASSERT(cond, msg)
#define IDMR_OFFSET_ASSERT(type, member, offset)
#define IDMR_INLINE inline /* functions shared by host and kernels */
#else
#include <stddef.h>
#define IDMR_INLINE static inline
#ifdef __cplusplus /* host C++ that reads the scene (io/gltf/gltf.cc) */
#define IDMR_STATIC_ASSERT(cond, msg) static_assert(cond, msg)
#define IDMR_OFFSET_ASSERT(type, member, offset)                                               \
    static_assert(offsetof(type, member) == (offset),                                          \
                  #type "." #member " must be at byte " #offset)
#else
#define IDMR_STATIC_ASSERT(cond, msg) _Static_assert(cond, msg)
#define IDMR_OFFSET_ASSERT(type, member, offset) \
    _Static_assert(offsetof(type, member) == (offset), #type "." #member " must be at byte " #offset)
#endif
#endif

#endif
