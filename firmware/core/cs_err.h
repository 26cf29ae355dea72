/* cs_err: the one table of status codes for the whole product.
 * Core functions that act return a cs_err_t; the host turns a code into a sentence with
 * cs_err_text() (host/cs_err_text.c), built from the same X-macro so the two never disagree.
 * The core itself holds no strings (no flash spent on text on an 8-bit target). */
#ifndef CS_ERR_H
#define CS_ERR_H

/* X(name, value, sentence). Values are stable: they travel on the wire (docs/protocol.md).
 * 0 is success; 1 is "iterator finished", which is not an error. */
#define CS_ERR_TABLE(X)                                                                        \
    X(CS_OK, 0, "success")                                                                     \
    X(CS_END, 1, "no more items (iteration finished)")                                        \
    X(CS_ERR_ARG, 2, "invalid argument")                                                       \
    X(CS_ERR_RANGE, 3, "value outside the fixed-point format's accepted range")                \
    X(CS_ERR_OVERFLOW, 4, "arithmetic overflow: result does not fit its fixed-point format")   \
    X(CS_ERR_DEGREE, 5, "unsupported curve degree")                                            \
    X(CS_ERR_FULL, 6, "buffer or queue full")                                                  \
    X(CS_ERR_EMPTY, 7, "buffer or queue empty")                                                \
    X(CS_ERR_TOLERANCE, 8, "tolerance too small or too large for the fixed-point format")      \
    X(CS_ERR_DEPTH, 9, "subdivision depth limit reached before the tolerance was met")         \
    X(CS_ERR_DEGENERATE, 10, "degenerate geometry (zero length, coincident or collinear data)") \
    X(CS_ERR_WEIGHT, 11, "rational weight not positive or outside the accepted range")         \
    X(CS_ERR_KNOTS, 12, "knot vector not non-decreasing or inconsistent with the degree")      \
    X(CS_ERR_SINGULAR, 13, "singular system: cannot be solved")                                \
    X(CS_ERR_LIMIT, 14, "move outside the machine's travel limits")                            \
    X(CS_ERR_STATE, 15, "operation not allowed in the current state")                          \
    X(CS_ERR_CRC, 16, "frame check (CRC) failed")                                              \
    X(CS_ERR_FRAME, 17, "malformed frame")                                                     \
    X(CS_ERR_SEQ, 18, "unexpected sequence number")                                            \
    X(CS_ERR_TIMEOUT, 19, "timed out")                                                         \
    X(CS_ERR_UNSUPPORTED, 20, "unsupported operation or message")                              \
    X(CS_ERR_IO, 21, "input/output error")                                                     \
    X(CS_ERR_PARSE, 22, "input could not be parsed")                                          \
    X(CS_ERR_LEASED, 23, "the mailbox is leased by another client")

#define CS_ERR_ENUM_(name, value, text) name = value,
typedef enum { CS_ERR_TABLE(CS_ERR_ENUM_) CS_ERR_COUNT_ } cs_err_t;
#undef CS_ERR_ENUM_

#endif
