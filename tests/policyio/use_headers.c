/*
 * Includes every header generated for the tests and takes each object's address, so that
 * a compiler for another target (avr-gcc for the ATmega128, g++ in C++20 mode) can check
 * that the generated headers compile there without warnings.
 */
#include "net12_policy.h"
#include "net12_table.h"
#include "prob_policy.h"
#include "prob_table.h"

#ifdef __cplusplus
extern "C" {
#endif
const void *qnav_test_generated_objects(int which);
#ifdef __cplusplus
}
#endif

const void *qnav_test_generated_objects(int which)
{
    switch (which) {
    case 0:
        return &net12_policy;
    case 1:
        return net12_table;
    case 2:
        return &prob_policy;
    default:
        return prob_table;
    }
}
