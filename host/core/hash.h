/* hash.h — FNV-1a, the 64-bit hash of the fingerprints and checksums idmr writes and compares
 * (the saved simulation's, the MPI ranks' agreement on a run). Not for anything an adversary
 * chooses: it only tells files and runs apart. */
#ifndef IDMR_HASH_H
#define IDMR_HASH_H

#include <stddef.h>
#include <stdint.h>

#define HASH_FNV1A_START 0xcbf29ce484222325ull

/* FNV-1a over `size` bytes at `bytes`, continuing `hash` (HASH_FNV1A_START to begin). */
static inline uint64_t hash_fnv1a(uint64_t hash, const void *bytes, size_t size)
{
    const unsigned char *b = bytes;
    for (size_t i = 0; i < size; i++)
        hash = (hash ^ b[i]) * 0x100000001b3ull;
    return hash;
}

#endif
