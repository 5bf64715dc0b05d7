/*
 * tap.h - a tiny TAP test harness (Automake's tap-driver reads it).
 * Asserts print both operands and are never compiled out.
 */
#ifndef WM_TAP_H
#define WM_TAP_H

#include <stdio.h>
#include <stdlib.h>

static int tap_n, tap_failed;

#define TAP_OK(cond, ...)                                                      \
    do                                                                         \
    {                                                                          \
        ++tap_n;                                                               \
        if (cond)                                                              \
            printf("ok %d - ", tap_n);                                         \
        else                                                                   \
        {                                                                      \
            ++tap_failed;                                                      \
            printf("not ok %d - ", tap_n);                                     \
        }                                                                      \
        printf(__VA_ARGS__);                                                   \
        printf("\n");                                                          \
        if (!(cond))                                                           \
            printf("#   failed at %s:%d: %s\n", __FILE__, __LINE__, #cond);    \
    } while (0)

/* Compare two integers, printing both on failure. */
#define TAP_EQ(a, b, ...)                                                      \
    do                                                                         \
    {                                                                          \
        long long tap_a = (long long)(a), tap_b = (long long)(b);              \
        TAP_OK(tap_a == tap_b, __VA_ARGS__);                                   \
        if (tap_a != tap_b)                                                    \
            printf("#   %s = %lld, %s = %lld\n", #a, tap_a, #b, tap_b);        \
    } while (0)

#define TAP_SKIP(why) printf("ok %d - # SKIP %s\n", ++tap_n, why)

/* Ends main(): prints the plan and returns the exit status. */
#define TAP_DONE()                                                             \
    (printf("1..%d\n", tap_n), tap_failed ? EXIT_FAILURE : EXIT_SUCCESS)

#endif /* WM_TAP_H */
