/* request_internal.h — what request.c shares with the decoders of its other sections
 * (request_curves.c): its strict readers that name the JSON path of a bad value. */
#ifndef ISM_REQUEST_INTERNAL_H
#define ISM_REQUEST_INTERNAL_H

#include <jansson.h>
#include "proto/json_writer.h"
#include "proto/request.h"

/* An object whose keys are all in known (NULL-terminated); 400 naming the unknown one. */
bool ism_rq_check_fields(const json_t *obj, const char *path, const char *const *known,
                         ism_req_error *err);
/* A finite number; 400 otherwise. */
bool ism_rq_read_number(const json_t *v, const char *path, double *out, ism_req_error *err);
const char *ism_rq_type_name(const json_t *v);
void ism_rq_path_key(char out[160], const char *parent, const char *key);
void ism_rq_path_index(char out[160], const char *parent, size_t i);

/* "curves" (request_curves.c): decoded into req->curves; 400 naming the path. */
bool ism_request_decode_curves(const json_t *v, ism_request *req, ism_req_error *err);
void ism_request_free_curves(ism_request *req);

/* "curves" as a member of the open object w, when there are any: the sources as written
 * (canonical request) or, with tape_text, each expression's compiled canonical text (key). */
void ism_request_write_curves(ism_jw *w, const ism_request *req, bool tape_text);

#endif
