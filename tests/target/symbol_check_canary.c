/*
 * Deliberately bad code for the symbol checker's own test: it uses the heap, printf and
 * float arithmetic, so check_symbols.cmake must reject it (CTest WILL_FAIL). It is built
 * into a static library only and never run.
 */
#include <stdio.h>
#include <stdlib.h>

int qnav_canary_bad(int n);

int qnav_canary_bad(int n)
{
    volatile float x = (float)n;
    char *p = malloc(16);
    int r;
    x = x / 3.0f + 1.5f;
    r = (int)x;
    if (p != NULL) {
        r += sprintf(p, "%d", r);
        free(p);
    }
    return r;
}
