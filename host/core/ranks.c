/* ranks.c — the MPI ranks of one run (see ranks.h). Without IDMR_MPI (a build without MPI) the
 * process is rank 0 of 1 and every call is a no-op. With it, MPI is started only when mpirun
 * launched the process; the collectives are non-blocking calls polled with a short sleep, so a
 * waiting rank leaves the cores to the ranks that compute. */
#include "core/ranks.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "core/error.h"
#include "core/progress.h"

#if IDMR_MPI
#include <limits.h>
#include <mpi.h>
#endif

#define RANKS_MESSAGE_MAX 2048

static int my_rank;       /* 0 without MPI */
static int rank_count = 1;

#if IDMR_MPI
static int active;        /* MPI started: more than one rank may run */
static int broken;        /* a sync saw a failure: no more communication */
static int failed_code;   /* the failing rank's exit code, once broken */
static char failure[RANKS_MESSAGE_MAX + 64]; /* "rank R of N: message", once broken */
static int exit_code;     /* this rank's exit code, from ranks_finish() (0 before) */
static int failure_said;  /* the failing rank had a message (a usage error prints its own) */
#endif

int ranks_rank(void) { return my_rank; }
int ranks_count(void) { return rank_count; }

int ranks_built(void)
{
#if IDMR_MPI
    return 1;
#else
    return 0;
#endif
}

void ranks_split(unsigned int total, unsigned int *first, unsigned int *count)
{
    uint64_t begin = (uint64_t)total * (uint64_t)my_rank / (uint64_t)rank_count;
    uint64_t end = (uint64_t)total * ((uint64_t)my_rank + 1) / (uint64_t)rank_count;
    *first = (unsigned int)begin;
    *count = (unsigned int)(end - begin);
}

/* Whether mpirun (Open MPI, or a PMI/PMIx launcher) started this process. */
static int launched_by_mpirun(void)
{
    static const char *const names[] = {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK",
                                        "PMI_SIZE"};
    for (size_t i = 0; i < sizeof names / sizeof *names; i++)
        if (getenv(names[i]))
            return 1;
    return 0;
}

#if IDMR_MPI

const char *ranks_library(void)
{
    static char version[MPI_MAX_LIBRARY_VERSION_STRING];
    int length = 0;
    if (!version[0] && MPI_Get_library_version(version, &length) == MPI_SUCCESS) {
        char *newline = strchr(version, '\n');
        if (newline)
            *newline = '\0';
        char *comma = strchr(version, ',');
        if (comma) /* "Open MPI v4.1.4, package: ...": the name and version */
            *comma = '\0';
    }
    return version;
}

void ranks_init(int *argc, char ***argv)
{
    if (!launched_by_mpirun())
        return;
    int provided;
    /* Only the main thread calls MPI (the device threads of sppm.c never do). */
    if (MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) {
        fprintf(stderr, "idmr: MPI_Init_thread failed\n");
        exit(IDMR_EXIT_FAILURE);
    }
    active = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &my_rank);
    MPI_Comm_size(MPI_COMM_WORLD, &rank_count);
    if (my_rank != 0) {
        /* One voice: rank 0's. The others print nothing on stdout, no warnings, no progress. */
        if (!freopen("/dev/null", "w", stdout))
            fprintf(stderr, "idmr: rank %d: cannot silence standard output\n", my_rank);
        warn_silence(1);
        progress_set_quiet(1);
    }
}

/* Waits for `request`, sleeping between polls (Open MPI's blocking calls spin on a core). */
static void wait_for(MPI_Request *request)
{
    int done = 0;
    MPI_Test(request, &done, MPI_STATUS_IGNORE);
    while (!done) {
        struct timespec pause = {0, 50 * 1000};
        nanosleep(&pause, NULL);
        MPI_Test(request, &done, MPI_STATUS_IGNORE);
    }
}

static void allreduce(void *data, int count, MPI_Datatype type, MPI_Op op)
{
    MPI_Request request;
    MPI_Iallreduce(MPI_IN_PLACE, data, count, type, op, MPI_COMM_WORLD, &request);
    wait_for(&request);
}

static void broadcast_from(void *data, size_t bytes, int root)
{
    for (size_t done = 0; done < bytes;) {
        size_t part = bytes - done < (size_t)INT_MAX ? bytes - done : (size_t)INT_MAX;
        MPI_Request request;
        MPI_Ibcast((char *)data + done, (int)part, MPI_BYTE, root, MPI_COMM_WORLD, &request);
        wait_for(&request);
        done += part;
    }
}

int ranks_sync(int status, int *flag)
{
    if (!active || broken)
        return status || broken ? -1 : 0;
    /* the lowest failing rank wins the maximum of (ranks - rank) */
    int agreed[2] = {status ? rank_count - my_rank : 0, flag ? (*flag != 0) : 0};
    allreduce(agreed, 2, MPI_INT, MPI_MAX);
    if (flag)
        *flag = agreed[1];
    if (!agreed[0])
        return 0;
    int failing = rank_count - agreed[0];
    struct {
        int code;
        char message[RANKS_MESSAGE_MAX];
    } sent;
    memset(&sent, 0, sizeof sent);
    if (my_rank == failing) {
        sent.code = exit_code ? exit_code : error_code();
        snprintf(sent.message, sizeof sent.message, "%s", error_message());
    }
    broadcast_from(&sent, sizeof sent, failing);
    broken = 1;
    failed_code = sent.code ? sent.code : IDMR_EXIT_FAILURE;
    failure_said = sent.message[0] != '\0';
    snprintf(failure, sizeof failure, "rank %d of %d: %s", failing, rank_count,
             failure_said ? sent.message : "failed (see its messages above)");
    if (my_rank != failing)
        error_set(failed_code, "%s", failure);
    return -1;
}

int ranks_finish(int code)
{
    if (!active)
        return code;
    exit_code = code;
    ranks_sync(code ? -1 : 0, NULL);
    int result = broken ? failed_code : code;
    if (broken && my_rank == 0 && failure_said)
        fprintf(stderr, "idmr: %s\n", failure);
    fflush(stdout);
    fflush(stderr);
    MPI_Finalize();
    active = 0;
    return result;
}

void ranks_sum_words(uint64_t *words, size_t n)
{
    if (!active || rank_count < 2)
        return;
    /* Whether any sum could pass 2^64: only where some word is above 2^64 / ranks. */
    uint64_t largest = 0;
    for (size_t t = 0; t < n; t++)
        largest = words[t] > largest ? words[t] : largest;
    allreduce(&largest, 1, MPI_UINT64_T, MPI_MAX);
    uint64_t *high = NULL;
    if (largest > UINT64_MAX / (uint64_t)rank_count) {
        /* Rare (words near the saturation limit): the sums of the words' upper halves tell a
         * sum of 2^63 or more (then saturated) from one that is exact in 64 bits. */
        high = xmalloc((n ? n : 1) * sizeof *high);
        for (size_t t = 0; t < n; t++)
            high[t] = words[t] >> 32;
    }
    const size_t chunk = (size_t)1 << 28;
    for (size_t done = 0; done < n; done += chunk) {
        int part = (int)(n - done < chunk ? n - done : chunk);
        allreduce(words + done, part, MPI_UINT64_T, MPI_SUM);
        if (high)
            allreduce(high + done, part, MPI_UINT64_T, MPI_SUM);
    }
    for (size_t t = 0; high && t < n; t++)
        if (high[t] >= ((uint64_t)1 << 31))
            words[t] = UINT64_MAX;
    free(high);
}

void ranks_broadcast(void *data, size_t bytes)
{
    if (active && rank_count > 1)
        broadcast_from(data, bytes, 0);
}

void ranks_broadcast_from(void *data, size_t bytes, int root)
{
    if (active && rank_count > 1)
        broadcast_from(data, bytes, root);
}

#else /* no MPI in this build: one rank */

const char *ranks_library(void) { return ""; }
void ranks_init(int *argc, char ***argv)
{
    (void)argc, (void)argv;
    /* N copies of a build without MPI would each run the whole command into one OUTDIR. */
    const char *size = getenv("OMPI_COMM_WORLD_SIZE");
    if (!size)
        size = getenv("PMI_SIZE");
    if (launched_by_mpirun() && size && atoi(size) > 1) {
        fprintf(stderr, "idmr: this idmr was built without MPI (`idmr devices`): run it without "
                        "mpirun, or build it where Open MPI is installed\n");
        exit(IDMR_EXIT_INPUT);
    }
}
int ranks_finish(int code) { return code; }
int ranks_sync(int status, int *flag) { (void)flag; return status ? -1 : 0; }
void ranks_sum_words(uint64_t *words, size_t n) { (void)words, (void)n; }
void ranks_broadcast(void *data, size_t bytes) { (void)data, (void)bytes; }
void ranks_broadcast_from(void *data, size_t bytes, int root)
{
    (void)data, (void)bytes, (void)root;
}

#endif
