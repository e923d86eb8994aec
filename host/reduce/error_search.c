/* error_search.c — bracket and safeguarded interpolation on log D for `--max-error`
 * (error_search.h). */
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

/* What the verdict compares with E: error + standard error. */
static double verdict_value(const error_search_step *s)
{
    return s->error + s->standard_error;
}

/* log D where the line through steps a and b crosses E: in (log D, log value) where both values
 * are above 0 (the error falls roughly as a power of D), else in (log D, value) (D = 1 has 0).
 * NAN where the line does not fall as D grows (noise) or a and b coincide. */
static double crossing_log_target(const error_search_step *a, const error_search_step *b,
                                  double max_error)
{
    double xa = log(a->target), xb = log(b->target);
    double ya = verdict_value(a), yb = verdict_value(b), y = max_error;
    if (ya > 0 && yb > 0 && max_error > 0) {
        ya = log(ya);
        yb = log(yb);
        y = log(max_error);
    }
    double slope = (yb - ya) / (xb - xa);
    if (!(slope < 0) || !isfinite(slope))
        return NAN;
    return xa + (y - ya) / slope;
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
    /* hi: the smallest D measured to pass (index hi_index); lo: the largest measured to fail
     * below it (index lo_index; 0 while none has). */
    double hi = 1.0, lo = 0.0;
    size_t hi_index = 0, lo_index = 0, previous_hi_index = 0;
    double log_step = log1p(step);
    error_search_step *s;
    double inside = 0.95 * log_step; /* a step, less rounding's room to land just outside it */
    /* Bracket: down while the steps pass, to the floor at most. The first step goes down by
     * ERROR_SEARCH_BRACKET; later ones to half a step below where the line through the last two
     * passing steps crosses E (a failure there brackets the crossing closely; ERROR_SEARCH_BRACKET
     * where the line does not fall), at most ERROR_SEARCH_FIRST_JUMP down on the line from D = 1
     * and ERROR_SEARCH_LONGEST_JUMP on the others, and at least `least_jump` (in log D): a step
     * at first, doubled by each pass (which the line did not foresee), so that a line that keeps
     * stopping short gallops. */
    double least_jump = inside;
    while (floor < hi && out->count < ERROR_SEARCH_MAX_STEPS) {
        double jump = log(ERROR_SEARCH_BRACKET); /* down from hi, in log D */
        if (hi_index > 0) {
            double crossing = crossing_log_target(&out->steps[previous_hi_index],
                                                  &out->steps[hi_index], max_error);
            if (isfinite(crossing))
                jump = log(hi) - (crossing - 0.5 * log_step);
            double longest =
                previous_hi_index == 0 ? ERROR_SEARCH_FIRST_JUMP : ERROR_SEARCH_LONGEST_JUMP;
            jump = fmin(log(longest), fmax(least_jump, jump));
        }
        double target = fmax(floor, hi * exp(-jump));
        if (measure_at(target, max_error, measure, context, out, &s))
            goto failed;
        if (!s->passes) {
            lo = target;
            lo_index = out->count - 1;
            break;
        }
        if (hi_index > 0)
            least_jump *= 2;
        previous_hi_index = hi_index;
        hi = target;
        hi_index = out->count - 1;
    }
    /* Narrow [lo, hi] on log D until it is within a step: aim half a step above where the line
     * through the two ends crosses E (a pass there and a failure a step below end the search),
     * kept (nearly) a step inside each end so that every measure narrows the bracket by about
     * one; a bisection wherever that line says nothing, the bracket is within two steps, or the
     * last two steps did not halve it. */
    double width_before[2] = {INFINITY, INFINITY}; /* the bracket one and two steps ago */
    while (lo > 0 && hi / lo > 1.0 + step && out->count < ERROR_SEARCH_MAX_STEPS) {
        double width = log(hi / lo), log_lo = log(lo);
        double target = sqrt(lo * hi);
        double crossing =
            crossing_log_target(&out->steps[lo_index], &out->steps[hi_index], max_error);
        if (width <= 0.5 * width_before[1] || width_before[1] == INFINITY)
            if (width > 2 * log_step && isfinite(crossing))
                target = exp(fmin(fmax(crossing + 0.5 * log_step, log_lo + inside),
                                  log_lo + width - inside));
        width_before[1] = width_before[0];
        width_before[0] = width;
        if (measure_at(target, max_error, measure, context, out, &s))
            goto failed;
        if (s->passes) {
            hi = target;
            hi_index = out->count - 1;
        } else {
            lo = target;
            lo_index = out->count - 1;
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
