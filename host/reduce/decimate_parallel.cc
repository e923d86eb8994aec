// decimate_parallel.cc — decimate_many() (see decimate.h): a pool of threads that take meshes,
// largest first, from one shared counter; each mesh is decimated by decimate_mesh(), with the
// threads the pool leaves over (threads / meshes, at least 1) inside it, and the progress bar,
// when given, advances by its input vertices once it is done.
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <mutex>
#include <thread>
#include <vector>

extern "C" {
#include "reduce/decimate.h"
#include "core/error.h"
}

extern "C" size_t decimate_many(const decimate_input *in, decimate_output *out, int *status,
                                char (*messages)[512], size_t count, decimate_method method,
                                unsigned int threads, progress *bar)
{
    std::mutex shown;
    std::vector<size_t> order(count);
    for (size_t i = 0; i < count; i++)
        order[i] = i;
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        return in[a].triangle_count > in[b].triangle_count;
    });
    if (threads < 1)
        threads = 1;
    unsigned int inner = count < threads ? threads / (unsigned int)count : 1;
    std::atomic<size_t> next(0), failed(0);
    auto worker = [&]() {
        for (;;) {
            size_t k = next.fetch_add(1);
            if (k >= count)
                return;
            size_t i = order[k];
            decimate_input job = in[i];
            job.threads = inner;
            status[i] = decimate_mesh(&job, method, &out[i]);
            if (status[i]) {
                failed++;
                if (messages)
                    std::snprintf(messages[i], sizeof messages[i], "%s", error_message());
            }
            if (bar) {
                std::lock_guard<std::mutex> lock(shown);
                progress_advance(bar, in[i].vertex_count, nullptr);
            }
        }
    };
    std::vector<std::thread> pool;
    for (unsigned int t = 1; t < threads && t < count; t++)
        pool.emplace_back(worker);
    worker();
    for (auto &thread : pool)
        thread.join();
    return failed;
}
