/* factor_stop.c — the importance pass's stop rule on the decimation factors (see factor_stop.h):
 * the factor and ranking changes between checkpoints, and the rule over them. */
#include "reduce/factor_stop.h"

#include <math.h>
#include <stdlib.h>

#include "core/error.h"

double factor_change(const uint64_t *before, const uint64_t *after, size_t count)
{
    double moved = 0, total = 0;
    for (size_t m = 0; m < count; m++) {
        moved += fabs((double)after[m] - (double)before[m]);
        total += (double)before[m];
    }
    return total > 0 ? moved / total : 0.0;
}

typedef struct ranked {
    double value;
    size_t index;
} ranked;

static int by_value(const void *a, const void *b)
{
    double x = ((const ranked *)a)->value, y = ((const ranked *)b)->value;
    return (x > y) - (x < y);
}

void mean_ranks(const double *values, size_t n, double *ranks)
{
    ranked *sorted = xmalloc((n ? n : 1) * sizeof *sorted);
    for (size_t i = 0; i < n; i++)
        sorted[i] = (ranked){values[i], i};
    qsort(sorted, n, sizeof *sorted, by_value);
    for (size_t i = 0; i < n;) {
        size_t j = i + 1;
        while (j < n && sorted[j].value == sorted[i].value)
            j++;
        double mean = 0.5 * (double)(i + 1 + j); /* mean of ranks i+1 .. j */
        for (size_t k = i; k < j; k++)
            ranks[sorted[k].index] = mean;
        i = j;
    }
    free(sorted);
}

double ranking_change(const double *ranks_before, const double *ranks_after, size_t n)
{
    if (n < 2)
        return 0.0;
    /* Pearson's correlation of the ranks (exact with ties), about the mean rank (n + 1) / 2. */
    double centre = 0.5 * ((double)n + 1), covariance = 0, var_before = 0, var_after = 0;
    for (size_t i = 0; i < n; i++) {
        double x = ranks_before[i] - centre, y = ranks_after[i] - centre;
        covariance += x * y;
        var_before += x * x;
        var_after += y * y;
    }
    if (!(var_before > 0) || !(var_after > 0))
        return 0.0;
    double rho = covariance / sqrt(var_before * var_after);
    return 1.0 - fmax(-1.0, fmin(1.0, rho));
}

int factor_stop_update(factor_stop *rule, double factor_change, double ranking_change)
{
    rule->checkpoints++;
    int factors_calm = factor_change >= 0 && factor_change < rule->tolerance;
    int ranking_calm = !(rule->ranking_tolerance > 0) ||
                       (ranking_change >= 0 && ranking_change < rule->ranking_tolerance);
    rule->calm = rule->tolerance > 0 && factors_calm && ranking_calm ? rule->calm + 1 : 0;
    return rule->calm >= FACTOR_STOP_CALM;
}
