/* test_json_writer.c — the JSON builder: output parses with jansson, strings survive escaping,
 * doubles and floats come back bit-exact from their shortest text, commas and nesting are
 * right, misuse is reported instead of producing broken text. */
#include <criterion/criterion.h>
#include <jansson.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "proto/json_writer.h"

Test(json_writer, nested_document_parses_back)
{
    ism_jw w;
    ism_jw_init(&w);
    ism_jw_object(&w);
    ism_jw_key(&w, "s");
    ism_jw_string(&w, "quote \" backslash \\ newline \n tab \t bell \a utf8 \xc3\xa9");
    ism_jw_key(&w, "a");
    ism_jw_array(&w);
    ism_jw_int(&w, -3);
    ism_jw_uint(&w, 9007199254740993ull);
    ism_jw_bool(&w, true);
    ism_jw_null(&w);
    ism_jw_array(&w);
    ism_jw_array_end(&w);
    ism_jw_object(&w);
    ism_jw_object_end(&w);
    ism_jw_array_end(&w);
    ism_jw_key(&w, "nan");
    ism_jw_number(&w, NAN);
    ism_jw_object_end(&w);
    size_t n;
    char *text = ism_jw_take(&w, &n);
    cr_assert_not_null(text);
    cr_expect_eq(strlen(text), n);
    json_error_t je;
    json_t *doc = json_loadb(text, n, JSON_REJECT_DUPLICATES, &je);
    cr_assert_not_null(doc, "%s: %s", text, je.text);
    cr_expect_str_eq(json_string_value(json_object_get(doc, "s")),
                     "quote \" backslash \\ newline \n tab \t bell \a utf8 \xc3\xa9");
    json_t *a = json_object_get(doc, "a");
    cr_expect_eq(json_array_size(a), 6);
    cr_expect_eq(json_integer_value(json_array_get(a, 0)), -3);
    cr_expect(json_is_null(json_object_get(doc, "nan")));
    json_decref(doc);
    free(text);
}

Test(json_writer, doubles_round_trip_from_shortest_text)
{
    srand(7);
    const double fixed[] = {0.1, 1.0 / 3, 1e-9, 1e300, -2.5e-308, 123456789012345678.0,
                            0.30000000000000004, 5e-324, 1.7976931348623157e308};
    char buf[32];
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++)
        cr_expect_eq(strtod(ism_jw_format_double(fixed[i], buf), NULL), fixed[i], "%s", buf);
    cr_expect_str_eq(ism_jw_format_double(0.1, buf), "0.1");
    cr_expect_str_eq(ism_jw_format_double(1.0, buf), "1");
    cr_expect_str_eq(ism_jw_format_double(-0.0, buf), "0");
    for (int i = 0; i < 20000; i++) {
        uint64_t bits = ((uint64_t)rand() << 42) ^ ((uint64_t)rand() << 21) ^ (uint64_t)rand();
        double v;
        memcpy(&v, &bits, sizeof v);
        if (!isfinite(v))
            continue;
        ism_jw_format_double(v, buf);
        cr_assert_eq(strtod(buf, NULL), v, "%s", buf);
        /* and jansson reads it as the same value */
        json_t *j = json_loads(buf, JSON_DECODE_ANY, NULL);
        cr_assert_not_null(j, "%s", buf);
        cr_assert_eq(json_number_value(j), v, "%s", buf);
        json_decref(j);
    }
}

Test(json_writer, floats_round_trip)
{
    srand(11);
    for (int i = 0; i < 20000; i++) {
        float f = (float)((rand() / (double)RAND_MAX - 0.5) * pow(10, rand() % 12 - 6));
        ism_jw w;
        ism_jw_init(&w);
        ism_jw_array(&w);
        ism_jw_float(&w, f);
        ism_jw_array_end(&w);
        char *t = ism_jw_take(&w, NULL);
        cr_assert_eq(strtof(t + 1, NULL), f, "%s", t);
        cr_assert_leq(strlen(t), 2 + 15);
        free(t);
    }
}

Test(json_writer, misuse_fails_instead_of_emitting_broken_text)
{
    ism_jw w;
    ism_jw_init(&w);
    ism_jw_object(&w);
    ism_jw_key(&w, "k");
    ism_jw_object_end(&w); /* a key without a value */
    cr_expect_null(ism_jw_take(&w, NULL));

    ism_jw_init(&w);
    ism_jw_array(&w); /* never closed */
    cr_expect_null(ism_jw_take(&w, NULL));

    ism_jw_init(&w);
    ism_jw_key(&w, "k"); /* a key outside an object */
    cr_expect(w.failed);
    ism_jw_free(&w);
}

/* decimals >= 0 rounds (trailing zeros and -0 dropped); decimals < 0 prints in full, the same
 * text as ism_jw_numbers (a clamp to 0 decimals would print [0,-3,1]). */
Test(json_writer, decimals_round_or_print_in_full)
{
    const double v[] = {0.123456789, -2.5, 1.0 / 3, -1e-4};
    ism_jw w;
    ism_jw_init(&w);
    ism_jw_numbers_decimals(&w, v, 4, 3);
    char *t = ism_jw_take(&w, NULL);
    cr_expect_str_eq(t, "[0.123,-2.5,0.333,0]");
    free(t);
    ism_jw_init(&w);
    ism_jw_numbers_decimals(&w, v, 4, -1);
    t = ism_jw_take(&w, NULL);
    ism_jw_init(&w);
    ism_jw_numbers(&w, v, 4);
    char *full = ism_jw_take(&w, NULL);
    cr_expect_str_eq(t, full);
    cr_expect_str_eq(t, "[0.123456789,-2.5,0.3333333333333333,-0.0001]");
    free(t);
    free(full);
}
