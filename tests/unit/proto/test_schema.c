/* test_schema.c — the published documents stay in step with the decoder: every field of
 * proto/request.schema.json is one the decoder knows (and no other), its defaults are the
 * decoder's, its limits are where the decoder draws the line, its preset list is the preset
 * table; proto/openapi.yaml documents the fixed Draco attribute ids. Run from the repository
 * root (the test runner does). */
#include <criterion/criterion.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/octree/polygonise.h"
#include "core/octree/tolerances.h"
#include "proto/draco_encode.h"
#include "proto/presets.h"
#include "proto/request.h"

static json_t *schema(void)
{
    json_error_t je;
    json_t *s = json_load_file("proto/request.schema.json", JSON_REJECT_DUPLICATES, &je);
    cr_assert_not_null(s, "proto/request.schema.json: %s (line %d)", je.text, je.line);
    return s;
}

static int decode_status(const char *json, ism_req_error *err)
{
    ism_request req;
    if (ism_request_decode(json, strlen(json), NULL, &req, err)) {
        ism_request_free(&req);
        return 200;
    }
    return err->status;
}

/* Every property of the schema object at `props` (under the request path `where`) is a field
 * the decoder knows: giving it a value of a silly type is not "unknown field". */
static void known_fields(json_t *props, const char *section)
{
    const char *name;
    json_t *v;
    json_object_foreach(props, name, v) {
        char json[256];
        if (section)
            snprintf(json, sizeof json, "{\"expr\": \"x\", \"%s\": {\"%s\": [true]}}",
                     section, name);
        else
            snprintf(json, sizeof json, "{\"expr\": \"x\", \"%s\": [true]}", name);
        ism_req_error err;
        decode_status(json, &err);
        cr_expect_null(strstr(err.message, "unknown field"), "%s: %s", json, err.message);
    }
    /* and a name the schema does not list is refused */
    char json[256];
    if (section)
        snprintf(json, sizeof json, "{\"expr\": \"x\", \"%s\": {\"not_in_schema\": 1}}", section);
    else
        snprintf(json, sizeof json, "{\"expr\": \"x\", \"not_in_schema\": 1}");
    ism_req_error err;
    cr_expect_eq(decode_status(json, &err), 400);
    cr_expect_not_null(strstr(err.message, "unknown field"), "%s", err.message);
}

Test(schema, fields_are_the_decoders)
{
    json_t *s = schema();
    json_t *props = json_object_get(s, "properties");
    cr_expect_eq(json_object_size(props), 15);
    known_fields(props, NULL);
    const char *sections[] = {"depth", "tolerances", "output"};
    for (int i = 0; i < 3; i++)
        known_fields(json_object_get(json_object_get(props, sections[i]), "properties"),
                     sections[i]);
    json_decref(s);
}

static double def(json_t *props, const char *section, const char *name)
{
    json_t *d = json_object_get(json_object_get(json_object_get(json_object_get(props, section),
                                                                "properties"), name), "default");
    cr_assert_not_null(d, "%s.%s has no default", section, name);
    return json_number_value(d);
}

Test(schema, defaults_are_the_decoders)
{
    json_t *s = schema();
    json_t *props = json_object_get(s, "properties");
    ism_request req;
    ism_req_error err;
    /* depth.max's default is the depth path's (under a bound the operator's limit is) */
    const char *off = "{\"expr\": \"x\", \"max_error\": null}";
    cr_assert(ism_request_decode(off, strlen(off), NULL, &req, &err));
    cr_expect_eq(def(props, "depth", "min"), req.poly.min_depth);
    cr_expect_eq(def(props, "depth", "max"), req.poly.max_depth);
    for (int i = 0; i < ISM_TOLERANCE_COUNT; i++)
        cr_expect_eq(def(props, "tolerances", ism_tolerances[i].key),
                     ism_tolerance_get(&req.poly, &ism_tolerances[i]), "%s",
                     ism_tolerances[i].key);
    cr_expect_eq(def(props, "output", "position_bits"), req.position_bits);
    cr_expect_eq(def(props, "output", "normal_bits"), req.normal_bits);
    cr_expect_eq(def(props, "output", "curvature_bits"), req.curvature_bits);
    json_t *q = json_object_get(json_object_get(props, "quality"), "default");
    cr_expect_str_eq(json_string_value(q), ism_quality_name(req.quality));
    json_t *names = json_object_get(json_object_get(props, "quality"), "enum");
    cr_expect_eq(json_array_size(names), ISM_QUALITY_COUNT);
    for (int i = 0; i < ISM_QUALITY_COUNT; i++)
        cr_expect_eq(ism_quality_lookup(json_string_value(json_array_get(names, i))), i);
    json_t *box = json_object_get(json_object_get(props, "box"), "default");
    for (int k = 0; k < 6; k++)
        cr_expect_eq(json_number_value(json_array_get(box, (size_t)k)), req.poly.box[k]);
    cr_expect_str_eq(json_string_value(json_object_get(
                         json_object_get(json_object_get(json_object_get(props, "output"),
                                                         "properties"), "format"), "default")),
                     ism_format_name(req.format));
    /* the schema's attributes default, named in a request, is what leaving them out gets */
    json_t *attrs = json_object_get(json_object_get(json_object_get(json_object_get(props,
                                        "output"), "properties"), "attributes"), "default");
    cr_assert(json_is_array(attrs), "output.attributes has no default");
    char listed[200];
    ism_request named;
    char *text = json_dumps(attrs, JSON_COMPACT);
    snprintf(listed, sizeof listed, "{\"expr\": \"x\", \"max_error\": null, \"output\": "
             "{\"attributes\": %s}}", text);
    free(text);
    cr_assert(ism_request_decode(listed, strlen(listed), NULL, &named, &err), "%s", err.message);
    cr_expect_eq(named.attributes, req.attributes, "the schema's default is not the decoder's");
    ism_request_free(&named);
    ism_request_free(&req);
    json_decref(s);
}

/* The decoder accepts the schema's maximum and refuses one past it (and the same at the
 * minimum). */
static void limit(json_t *props, const char *section, const char *name, double step)
{
    json_t *p = json_object_get(json_object_get(json_object_get(props, section), "properties"),
                                name);
    const char *bounds[2] = {"minimum", "maximum"};
    for (int b = 0; b < 2; b++) {
        json_t *v = json_object_get(p, bounds[b]);
        if (!v)
            continue;
        double at = json_number_value(v), past = b ? at + step : at - step;
        char json[256];
        ism_req_error err;
        snprintf(json, sizeof json, "{\"expr\": \"x\", \"%s\": {\"%s\": %.17g}}", section, name, at);
        cr_expect_eq(decode_status(json, &err), 200, "%s: %s", json, err.message);
        snprintf(json, sizeof json, "{\"expr\": \"x\", \"%s\": {\"%s\": %.17g}}", section, name, past);
        cr_expect_eq(decode_status(json, &err), 422, "%s", json);
    }
}

/* The schema's "tolerances" are the table's: the same names, and each one's range is the
 * table's (which the decoder and the polygoniser's check both use). */
Test(schema, tolerances_are_the_tables)
{
    json_t *s = schema();
    json_t *tol = json_object_get(json_object_get(json_object_get(s, "properties"),
                                                  "tolerances"), "properties");
    cr_expect_eq(json_object_size(tol), ISM_TOLERANCE_COUNT);
    for (int i = 0; i < ISM_TOLERANCE_COUNT; i++) {
        const ism_tolerance *t = &ism_tolerances[i];
        json_t *p = json_object_get(tol, t->key);
        cr_assert_not_null(p, "%s is not in the schema", t->key);
        cr_expect_eq(json_number_value(json_object_get(p, "minimum")), t->lo, "%s", t->key);
        cr_expect_eq(json_number_value(json_object_get(p, "maximum")), t->hi, "%s", t->key);
        cr_expect_str_eq(json_string_value(json_object_get(p, "type")),
                         t->is_int ? "integer" : "number", "%s", t->key);
    }
    json_decref(s);
}

Test(schema, limits_are_where_the_decoder_draws_the_line)
{
    json_t *s = schema();
    json_t *props = json_object_get(s, "properties");
    limit(props, "depth", "min", 1);
    limit(props, "tolerances", "gradient", 0.01);
    limit(props, "tolerances", "double_root_eps", 0.01);
    limit(props, "tolerances", "double_root_iters", 1);
    limit(props, "tolerances", "stitch", 1e-10);
    limit(props, "tolerances", "flat_normal", 0.01);
    limit(props, "tolerances", "flat_plane", 1e-7);
    limit(props, "output", "position_bits", 1);
    limit(props, "output", "normal_bits", 1);
    json_t *items = json_object_get(json_object_get(props, "box"), "items");
    cr_expect_eq(json_number_value(json_object_get(items, "maximum")), ISM_REQ_MAX_COORD);
    cr_expect_eq(json_number_value(json_object_get(json_object_get(props, "expr"), "maxLength")),
                 ISM_REQ_MAX_SOURCE);
    json_t *dmax = json_object_get(json_object_get(json_object_get(props, "depth"), "properties"),
                                   "max");
    cr_expect_eq(json_integer_value(json_object_get(dmax, "maximum")), ISM_MAX_DEPTH_LIMIT);
    json_decref(s);
}

Test(schema, presets_are_the_table)
{
    json_t *s = schema();
    json_t *e = json_object_get(json_object_get(json_object_get(s, "properties"), "preset"), "enum");
    cr_assert_eq(json_array_size(e), ism_preset_count());
    for (size_t i = 0; i < ism_preset_count(); i++)
        cr_expect_str_eq(json_string_value(json_array_get(e, i)), ism_preset_at(i)->name);
    json_decref(s);

    size_t n;
    char *text = ism_presets_json(&n);
    json_error_t je;
    json_t *doc = json_loadb(text, n, JSON_REJECT_DUPLICATES, &je);
    cr_assert_not_null(doc, "%s", je.text);
    json_t *list = json_object_get(doc, "presets");
    cr_expect_eq(json_array_size(list), ism_preset_count());
    for (size_t i = 0; i < json_array_size(list); i++) {
        json_t *p = json_array_get(list, i);
        cr_expect_gt(strlen(json_string_value(json_object_get(p, "about"))), 10);
        cr_expect_eq(json_array_size(json_object_get(p, "box")), 6);
    }
    json_decref(doc);
    free(text);
}

Test(schema, openapi_documents_the_attribute_ids)
{
    FILE *f = fopen("proto/openapi.yaml", "r");
    cr_assert_not_null(f);
    static char text[1 << 17];
    size_t n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[n] = '\0';
    const struct {
        int id;
        const char *name;
    } ids[] = {{ISM_DRACO_ID_POSITION, "position"},
               {ISM_DRACO_ID_NORMAL, "normal"},
               {ISM_DRACO_ID_MEAN_CURVATURE, "mean_curvature"},
               {ISM_DRACO_ID_GAUSS_CURVATURE, "gauss_curvature"},
               {ISM_DRACO_ID_CLASS, "class"}};
    for (size_t i = 0; i < 5; i++) {
        char row[64];
        snprintf(row, sizeof row, "| %d         | %-16s|", ids[i].id, ids[i].name);
        cr_expect_not_null(strstr(text, row), "openapi.yaml lacks the row '%s'", row);
    }
    cr_expect_not_null(strstr(text, "$ref: 'request.schema.json'"));
}
