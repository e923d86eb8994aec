/* ranks.h — the MPI ranks of one run (`mpirun -n N idmr ...`), behind a small API that a build
 * without MPI keeps as one rank.
 *
 * Built with -DIDMR_MPI=1 (the Makefile does so where it finds Open MPI), ranks_init() starts
 * MPI only when the process was launched by mpirun (its environment says so); run plainly, or
 * built without MPI, the process is rank 0 of 1 and every call below is a no-op, so idmr
 * behaves exactly as without MPI and prints nothing of it.
 *
 * Failures: ranks never wait for a rank that has failed. Every collective that carries data
 * (ranks_sum_words, ranks_broadcast) is called right after a ranks_sync() that succeeded on
 * all ranks, with no way to fail between the two; a rank that fails elsewhere unwinds and
 * meets the others at its next ranks_sync() (at the latest the one in ranks_finish(), at the
 * end of main), which matches theirs whatever line it is on, because collectives pair by their
 * order. Once a sync has seen a failure, every rank holds the failing rank's message and code
 * (the lowest failing rank's), ranks_sync() returns -1 from then on without communicating, and
 * the ranks unwind; ranks_finish() has rank 0 print that message, naming the rank.
 *
 * Waiting ranks sleep between polls (no busy wait): a rank that waits for another leaves it
 * the cores. */
#ifndef IDMR_RANKS_H
#define IDMR_RANKS_H

#include <stddef.h>
#include <stdint.h>

/* Starts MPI when launched by mpirun (MPI builds); ranks other than 0 then print nothing on
 * stdout and no warnings. Call once, first thing in main. */
void ranks_init(int *argc, char ***argv);

/* The last sync (a failure there or before names its rank; rank 0 prints it), then MPI's end.
 * `code` is this rank's exit code; returns the run's (a failed rank's code on every rank). */
int ranks_finish(int code);

int ranks_rank(void);  /* this process's rank, 0 without MPI */
int ranks_count(void); /* ranks in the run, 1 without MPI */
int ranks_built(void); /* 1 when this build has MPI (`idmr devices` says so) */
const char *ranks_library(void); /* the MPI library's version line, or "" */

/* Agrees on the status of all ranks: 0 when every rank passes status 0, else -1 with the error
 * of the lowest failing rank set (its message and code; "rank R of N: ..." on the other
 * ranks). *flag (may be NULL) becomes 1 on every rank when it is 1 on any (a stop). */
int ranks_sync(int status, int *flag);

/* After a successful ranks_sync(): words[0..n) becomes the sum over all ranks, exactly (as
 * 64-bit integers). A sum that would pass 2^64 becomes UINT64_MAX (callers check words against
 * their saturation limit, far below). */
void ranks_sum_words(uint64_t *words, size_t n);

/* After a successful ranks_sync(): rank 0's `bytes` at `data` copied to every rank; or rank
 * `root`'s (every rank passes the same root and size). */
void ranks_broadcast(void *data, size_t bytes);
void ranks_broadcast_from(void *data, size_t bytes, int root);

/* The photon paths [*first, *first + *count) of `total` that this rank traces: contiguous
 * ranges in rank order, as even as whole paths allow. */
void ranks_split(unsigned int total, unsigned int *first, unsigned int *count);

#endif
