/* cs_err_text: sentences and names expanded from CS_ERR_TABLE (firmware/core/cs_err.h). */
#include "cs_err_text.h"

const char *cs_err_text(cs_err_t e)
{
    switch (e) {
#define CS_ERR_TEXT_CASE_(name, value, text)                                                       \
    case name:                                                                                     \
        return text;
        CS_ERR_TABLE(CS_ERR_TEXT_CASE_)
#undef CS_ERR_TEXT_CASE_
    default:
        break;
    }
    return "unknown status code";
}

const char *cs_err_name(cs_err_t e)
{
    switch (e) {
#define CS_ERR_NAME_CASE_(name, value, text)                                                       \
    case name:                                                                                     \
        return #name;
        CS_ERR_TABLE(CS_ERR_NAME_CASE_)
#undef CS_ERR_NAME_CASE_
    default:
        break;
    }
    return "CS_ERR_?";
}
