/* parallel.c: a worker function run on several threads at once. */
#include "terrain_internal.h"

#include <pthread.h>

enum { MAX_THREADS = 256 };

uint32_t tsr__thread_count(uint32_t threads)
{
    return threads ? threads : tsr_cpu_count();
}

void tsr__run_threads(void *(*work)(void *), void *arg, uint32_t threads, uint32_t jobs)
{
    uint32_t nt = tsr__thread_count(threads);
    nt = nt > jobs ? jobs : nt;
    nt = nt > MAX_THREADS ? MAX_THREADS : nt;
    pthread_t th[MAX_THREADS];
    uint32_t started = 0;
    for (uint32_t k = 1; k < nt; k++)
        if (pthread_create(&th[started], NULL, work, arg) == 0)
            started++;
    work(arg);
    for (uint32_t k = 0; k < started; k++)
        pthread_join(th[k], NULL);
}
