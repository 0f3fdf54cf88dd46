/* log.h — one line per event on stderr, as `key=value` text or as one JSON object per line,
 * written with a single write(2) so lines from several threads and processes never mix
 * (or queued for a writer thread, see ism_log_async). */
#ifndef ISM_LOG_H
#define ISM_LOG_H

#include <stdbool.h>
#include <stddef.h>

typedef enum ism_log_format { ISM_LOG_TEXT, ISM_LOG_JSON } ism_log_format;
typedef enum ism_log_level { ISM_LOG_DEBUG, ISM_LOG_INFO, ISM_LOG_WARN, ISM_LOG_ERROR } ism_log_level;

/* Set once at start-up, before other threads log. */
void ism_log_setup(const char *program, ism_log_format format);
/* Parses "text" or "json"; false on anything else. */
bool ism_log_parse_format(const char *s, ism_log_format *out);

/* A named field of a structured line. */
typedef enum ism_log_kind { ISM_LF_STR, ISM_LF_INT, ISM_LF_NUM } ism_log_kind;
typedef struct ism_log_field {
    const char *name;
    ism_log_kind kind;
    const char *s;  /* ISM_LF_STR (NULL prints as "-" / null) */
    long long i;    /* ISM_LF_INT */
    double d;       /* ISM_LF_NUM (printed with 3 decimals) */
} ism_log_field;

#define ISM_LS(n, v) ((ism_log_field){.name = (n), .kind = ISM_LF_STR, .s = (v)})
#define ISM_LI(n, v) ((ism_log_field){.name = (n), .kind = ISM_LF_INT, .i = (long long)(v)})
#define ISM_LN(n, v) ((ism_log_field){.name = (n), .kind = ISM_LF_NUM, .d = (double)(v)})

/* One line: time, level, event name, then the fields in order. */
void ism_log_fields(ism_log_level level, const char *event, const ism_log_field *fields,
                    size_t n);

/* Writes d with three decimals, as printf's "%.3f" and the ISM_LF_NUM fields show it, into
 * out (cap bytes, terminated); returns its length. For other text carrying the same numbers
 * once per request (the Server-Timing header). */
size_t ism_log_number(char *out, size_t cap, double d);

/* Background writing (for a server's event loop): lines go into a bounded in-memory queue
 * that one thread writes out, in writes of whole lines of at most 4096 bytes (so they never
 * mix with other processes' lines on a shared pipe). A full queue drops the line instead of
 * blocking the caller (a stuck log reader must not stall the service); ism_log_dropped counts
 * them. ism_log_async(false) writes out everything queued and stops the thread. */
void ism_log_async(bool on);
unsigned long long ism_log_dropped(void);

/* One line with a free-text message (printf format) in the field "msg". */
void ism_logf(ism_log_level level, const char *event, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

#endif
