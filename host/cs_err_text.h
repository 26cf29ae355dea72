/* cs_err_text: the host-side sentence for each status code of firmware/core/cs_err.h.
 * Generated from the same X-macro table, so a code and its sentence never disagree; the core
 * itself carries no strings. */
#ifndef CS_ERR_TEXT_H
#define CS_ERR_TEXT_H

#include "cs_err.h"

/* The sentence for code e (static storage, never NULL); "unknown status code" for a value that
 * is not in the table. */
const char *cs_err_text(cs_err_t e);
/* The code's name as written in the table ("CS_ERR_RANGE"), or "CS_ERR_?" when unknown. */
const char *cs_err_name(cs_err_t e);

#endif
