/*
 * QNAV_CHECK_RESULT marks a function whose status must not be ignored (nanopb's
 * checkreturn): with gcc and clang a call that drops the result is a warning, and the
 * firmware builds with -Werror in CI. Other compilers get nothing.
 */
#ifndef QNAV_CHECK_H
#define QNAV_CHECK_H

#if defined(__GNUC__) || defined(__clang__)
#define QNAV_CHECK_RESULT __attribute__((warn_unused_result))
#else
#define QNAV_CHECK_RESULT
#endif

#endif /* QNAV_CHECK_H */
