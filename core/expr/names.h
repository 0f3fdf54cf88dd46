/* names.h — what a name in an expression can mean: a variable (x y z), a constant (pi e),
 * a function, a parameter or a let binding; and the rules a new parameter or let name must
 * follow (a valid identifier that shadows nothing). Internal to core/expr. */
#ifndef ISM_NAMES_H
#define ISM_NAMES_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>

enum ism_name_kind { ISM_N_PARAM, ISM_N_LET };

typedef struct ism_name {
    char name[64];
    int kind;
    uint32_t node;   /* graph node the name stands for */
} ism_name;

typedef struct ism_names {
    ism_name *items;
    size_t count, cap;
} ism_names;

enum ism_func { ISM_F_SQRT, ISM_F_SIN, ISM_F_COS, ISM_F_TAN, ISM_F_EXP, ISM_F_LOG, ISM_F_ABS,
                ISM_F_MIN, ISM_F_MAX, ISM_F_POW, ISM_F_COUNT };

typedef struct ism_func_info {
    const char *name;
    int min_args;
    int max_args;     /* -1: no upper bound */
} ism_func_info;

/* The function called name (len bytes), or -1. */
int ism_func_lookup(const char *name, size_t len);
const ism_func_info *ism_func_get(int f);

/* 0, 1, 2 for x, y, z; -1 otherwise. */
int ism_var_lookup(const char *name, size_t len);

/* true and *v for pi and e. */
bool ism_const_lookup(const char *name, size_t len, double *v);

const ism_name *ism_names_find(const ism_names *s, const char *name, size_t len);

/* Checks that name can be bound as a `what` ("parameter" or "let"): a valid identifier that
 * is neither a variable, function, constant, keyword nor already bound. On failure writes
 * a message into msg and returns false. */
bool ism_names_check_new(const ism_names *s, const char *name, size_t len, const char *what,
                         char *msg, size_t n);

/* Adds a binding (the caller checked it). False when out of memory. */
bool ism_names_add(ism_names *s, const char *name, size_t len, int kind, uint32_t node);

void ism_names_free(ism_names *s);

#endif
