/* progress.h — the monotonic clock for timings, the process's resident memory, and progress on
 * stderr for long work: a bar redrawn in place when stderr is a terminal, otherwise one line at
 * every tenth of the work. Work that may be short or long (loading a scene) shows nothing until
 * it has taken a while (progress_delay). */
#ifndef IDMR_PROGRESS_H
#define IDMR_PROGRESS_H

#ifdef __cplusplus
extern "C" {
#endif

/* Seconds on the monotonic clock. */
double monotonic_seconds(void);

/* The process's resident memory now, in bytes (/proc/self/statm); 0 where it cannot be read. */
unsigned long long resident_bytes(void);

typedef struct progress {
    const char *label;
    unsigned int total;
    int enabled;
    int terminal;
    unsigned int next_line; /* non-terminal: the next count that gets a line */
    unsigned int done;      /* what progress_advance() has added up */
    double start;
    double delay; /* seconds after start before anything is shown */
    int shown;    /* something was drawn */
} progress;

void progress_begin(progress *p, const char *label, unsigned int total, int enabled);
/* Shows nothing until `seconds` after progress_begin (then what is done by then). */
void progress_delay(progress *p, double seconds);
/* The work to do, as it is found on the way (an estimate made exact). */
void progress_set_total(progress *p, unsigned int total);
/* `done` of total finished; `detail` (may be NULL) is shown after the bar. */
void progress_update(progress *p, unsigned int done, const char *detail);
/* `amount` more finished (progress_update with the running sum). */
void progress_advance(progress *p, unsigned int amount, const char *detail);
void progress_end(progress *p);

/* The command line's --quiet for work that takes no options of its own (loading a scene): set
 * once by the option parser; progress_quiet() says whether it was (0 until then). */
void progress_set_quiet(int quiet);
int progress_quiet(void);

#ifdef __cplusplus
}
#endif

#endif
