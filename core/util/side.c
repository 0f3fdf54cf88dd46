/* side.c — a function on a thread of its own beside the caller's work (side.h). */
#include "core/util/side.h"

static void *side_main(void *arg)
{
    ism_side *s = arg;
    s->fn(s->arg);
    return NULL;
}

void ism_side_start(ism_side *s, bool thread, void (*fn)(void *arg), void *arg)
{
    s->fn = fn;
    s->arg = arg;
    s->started = thread && pthread_create(&s->tid, NULL, side_main, s) == 0;
    if (!s->started)
        fn(arg);
}

void ism_side_join(ism_side *s)
{
    if (s->started)
        pthread_join(s->tid, NULL);
    s->started = false;
}
