/* progress.c — clock, resident memory and progress display (see progress.h). */
#include "core/progress.h"
#include "core/ranks.h"

#include <stdio.h>
#include <time.h>
#include <unistd.h>

double monotonic_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

unsigned long long resident_bytes(void)
{
    FILE *f = fopen("/proc/self/statm", "r");
    unsigned long long size = 0, resident = 0;
    int read = f && fscanf(f, "%llu %llu", &size, &resident) == 2;
    if (f)
        fclose(f);
    long page = sysconf(_SC_PAGESIZE);
    return read && page > 0 ? resident * (unsigned long long)page : 0;
}

void progress_begin(progress *p, const char *label, unsigned int total, int enabled)
{
    p->label = label;
    p->total = total ? total : 1;
    p->enabled = enabled && ranks_rank() == 0; /* under mpirun, rank 0 reports */
    p->terminal = isatty(STDERR_FILENO);
    p->next_line = 0;
    p->done = 0;
    p->start = monotonic_seconds();
    p->delay = 0;
    p->shown = 0;
}

void progress_delay(progress *p, double seconds)
{
    p->delay = seconds;
}

void progress_set_total(progress *p, unsigned int total)
{
    p->total = total ? total : 1;
}

static int quiet;

void progress_set_quiet(int value)
{
    quiet = value;
}

int progress_quiet(void)
{
    return quiet;
}

void progress_advance(progress *p, unsigned int amount, const char *detail)
{
    p->done += amount;
    progress_update(p, p->done, detail);
}

void progress_update(progress *p, unsigned int done, const char *detail)
{
    if (!p->enabled)
        return;
    double elapsed = monotonic_seconds() - p->start;
    if (elapsed < p->delay)
        return;
    p->shown = 1;
    double fraction = (double)done / p->total;
    double remaining = done ? elapsed * (p->total - done) / done : 0;
    if (p->terminal) {
        char bar[31];
        int filled = (int)(fraction * 30 + 0.5);
        for (int i = 0; i < 30; i++)
            bar[i] = i < filled ? '#' : '.';
        bar[30] = '\0';
        fprintf(stderr, "\r%s [%s] %u/%u  %.1fs, %.1fs left  %s\033[K", p->label, bar, done,
                p->total, elapsed, remaining, detail ? detail : "");
        fflush(stderr);
    } else if (done >= p->next_line || done == p->total) {
        fprintf(stderr, "%s: %u/%u (%.0f%%) %.1fs %s\n", p->label, done, p->total,
                100.0 * fraction, elapsed, detail ? detail : "");
        p->next_line = done + (p->total + 9) / 10;
    }
}

void progress_end(progress *p)
{
    if (p->enabled && p->terminal && (p->shown || p->delay <= 0))
        fputc('\n', stderr);
}
