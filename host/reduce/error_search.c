/* error_search.c — bracket and bisection on log D for `--max-error` (error_search.h). */
#include "reduce/error_search.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"

/* Measures D into the next step of r; 0, or -1 (the measure's error set). */
static int measure_at(double target, double max_error, error_search_measure measure,
                      void *context, error_search_result *r, error_search_step **out)
{
    error_search_step *step = &r->steps[r->count];
    memset(step, 0, sizeof *step);
    if (measure(target, step, context))
        return -1;
    step->target = target;
    step->measured = 1;
    step->passes = step->error + step->standard_error <= max_error;
    r->count++;
    *out = step;
    return 0;
}

int error_search_run(double max_error, double step, double floor, error_search_measure measure,
                     void *context, error_search_result *out)
{
    memset(out, 0, sizeof *out);
    if (!(max_error >= 0) || !isfinite(max_error))
        return error_set(IDMR_EXIT_INPUT, "--max-error must be a finite number of at least 0, "
                                          "not %g", max_error);
    if (!(step > 0) || !isfinite(step))
        return error_set(IDMR_EXIT_INPUT, "--max-error-step must be above 0, not %g", step);
    if (!(floor > 0) || !isfinite(floor))
        return error_set(IDMR_EXIT_INPUT, "the search's floor must be above 0, not %g", floor);
    out->steps = xcalloc(ERROR_SEARCH_MAX_STEPS + 1, sizeof *out->steps);
    out->steps[0] = (error_search_step){.target = 1.0, .passes = 1};
    out->count = 1;
    double hi = 1.0, lo = 0.0;
    size_t hi_index = 0;
    error_search_step *s;
    /* Bracket: down by ERROR_SEARCH_BRACKET while the steps pass, to the floor at most. */
    while (floor < hi && out->count < ERROR_SEARCH_MAX_STEPS) {
        double target = fmax(floor, hi / ERROR_SEARCH_BRACKET);
        if (measure_at(target, max_error, measure, context, out, &s))
            goto failed;
        if (!s->passes) {
            lo = target;
            break;
        }
        hi = target;
        hi_index = out->count - 1;
    }
    /* Bisect on log D while the bracket is wider than a step. */
    while (lo > 0 && hi / lo > 1.0 + step && out->count < ERROR_SEARCH_MAX_STEPS) {
        double target = sqrt(lo * hi);
        if (measure_at(target, max_error, measure, context, out, &s))
            goto failed;
        if (s->passes) {
            hi = target;
            hi_index = out->count - 1;
        } else {
            lo = target;
        }
    }
    out->target = hi;
    out->chosen = hi_index;
    return 0;
failed:
    error_search_result_free(out);
    return -1;
}

void error_search_result_free(error_search_result *r)
{
    free(r->steps);
    memset(r, 0, sizeof *r);
}
