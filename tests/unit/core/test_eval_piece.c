/* test_eval_piece.c — f's smooth pieces (eval.h ism_eval_piece, ism_eval_piece_gradient) on
 * cube-minus-ball, f = max(max(|x|, |y|, |z|) − 1, 1.69 − |p|²), against its closed form: the
 * six faces and the ball are seven pieces, a ball point's piece does not depend on which
 * coordinate is largest there, and f on a face's piece is that face's plane (value and
 * gradient) on both sides of the cube's edges, where f itself takes another face; and what
 * each kink passes on each branch. */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>

#include "core/eval/eval.h"
#include "core/eval/workspace.h"
#include "core/expr/expr.h"

#define CMB "max(max(abs(x), abs(y), abs(z)) - 1, 1.69 - (x^2 + y^2 + z^2))"

static ism_tape *compile(const char *expr)
{
    ism_error err;
    ism_tape *t = ism_tape_compile(expr, NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t, "%s", err.message);
    return t;
}

/* A point of the face x_a = s (s = ±1) outside the ball, u, v its other coordinates. */
static void face_point(int a, int s, double u, double v, double p[3])
{
    p[a] = s;
    p[(a + 1) % 3] = u;
    p[(a + 2) % 3] = v;
}

Test(eval_piece, cube_minus_ball_has_seven_pieces)
{
    ism_tape *t = compile(CMB);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    cr_assert_eq(ism_tape_kinks(t), 6, "three max and three abs");
    ism_piece face[3][2];
    for (int a = 0; a < 3; a++)
        for (int s = 0; s < 2; s++) {
            double p[3], q[3];
            face_point(a, 2 * s - 1, 0.9, 0.95, p); /* |p|² = 2.7 > 1.69: on the cube */
            face_point(a, 2 * s - 1, -0.92, 0.91, q);
            face[a][s] = ism_eval_piece(t, ws, p[0], p[1], p[2]);
            cr_assert_neq(face[a][s], ISM_PIECE_NONE);
            cr_expect_eq(ism_eval_piece(t, ws, q[0], q[1], q[2]), face[a][s],
                         "two points of face %d, side %d", a, s);
        }
    /* the ball: points whose largest coordinate differs share one piece */
    ism_piece ball = ism_eval_piece(t, ws, 0.75, 0.1, 0.2); /* 1.69 − 0.6125 > 0.75 − 1 */
    cr_expect_eq(ism_eval_piece(t, ws, 0.1, -0.2, 0.75), ball, "inner max not on the path");
    cr_expect_eq(ism_eval_piece(t, ws, -0.1, 0.75, 0.05), ball);
    ism_piece all[7] = {face[0][0], face[0][1], face[1][0], face[1][1], face[2][0], face[2][1],
                        ball};
    for (int i = 0; i < 7; i++)
        for (int j = i + 1; j < 7; j++)
            cr_expect_neq(all[i], all[j], "pieces %d and %d", i, j);
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

Test(eval_piece, a_face_piece_is_its_plane_past_the_edge)
{
    ism_tape *t = compile(CMB);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    for (int a = 0; a < 3; a++)
        for (int s = -1; s <= 1; s += 2) {
            double p[3], g[3];
            face_point(a, s, 0.9, 0.95, p);
            ism_piece pc = ism_eval_piece(t, ws, p[0], p[1], p[2]);
            /* beyond the edge x_{a+1} = 1 (where f takes that face): still x_a·s − 1 */
            double q[3];
            face_point(a, s, 1.2, 0.3, q);
            q[a] = 0.8 * s;
            double v = ism_eval_piece_gradient(t, ws, pc, q[0], q[1], q[2], g);
            cr_expect_float_eq(v, 0.8 - 1, 1e-15, "face %d side %d: %g", a, s, v);
            for (int k = 0; k < 3; k++)
                cr_expect_eq(g[k], k == a ? s : 0, "face %d side %d: g[%d] = %g", a, s, k, g[k]);
            /* f there is the face x_{a+1} = 1's value, 0.2 */
            cr_expect_float_eq(ism_eval_point(t, ws, q[0], q[1], q[2]), 0.2, 1e-15);
        }
    /* the ball's piece: 1.69 − |p|², gradient −2p, also outside the cube */
    ism_piece ball = ism_eval_piece(t, ws, 0.75, 0.1, 0.2);
    double g[3], v = ism_eval_piece_gradient(t, ws, ball, 1.2, 0.3, -0.4, g);
    cr_expect_float_eq(v, 1.69 - (1.44 + 0.09 + 0.16), 1e-14);
    cr_expect_float_eq(g[0], -2.4, 1e-14);
    cr_expect_float_eq(g[1], -0.6, 1e-14);
    cr_expect_float_eq(g[2], 0.8, 1e-14);
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

/* A min, a max with a constant and an abs on the path: f = min(|x| − 1, max(y, 0.5)). */
Test(eval_piece, constant_operands_and_abs_signs)
{
    ism_tape *t = compile("min(abs(x) - 1, max(y, 0.5))");
    ism_eval_ws *ws = ism_eval_ws_new(t);
    ism_piece right = ism_eval_piece(t, ws, 0.2, 3, 0), left = ism_eval_piece(t, ws, -0.2, 3, 0);
    ism_piece ymax = ism_eval_piece(t, ws, 3, 0.7, 0), cst = ism_eval_piece(t, ws, 3, 0.1, 0);
    cr_expect_neq(right, left, "abs's sign is on the path");
    cr_expect_neq(ymax, cst);
    cr_expect_eq(ism_eval_piece(t, ws, 3, 0.1, 0), ism_eval_piece(t, ws, -3, 0.2, 0),
                 "abs is off the path where the max's constant is taken");
    double g[3];
    cr_expect_float_eq(ism_eval_piece_gradient(t, ws, left, 0.5, 3, 0, g), -1.5, 1e-15);
    cr_expect_eq(g[0], -1.0);
    cr_expect_float_eq(ism_eval_piece_gradient(t, ws, cst, 0, 9, 0, g), 0.5, 1e-15);
    cr_expect(g[0] == 0 && g[1] == 0 && g[2] == 0);
    cr_expect_float_eq(ism_eval_piece_gradient(t, ws, ymax, 0, -2, 0, g), -2, 1e-15);
    cr_expect_eq(g[1], 1.0);
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

/* ism_eval_piece_value is ism_eval_piece_gradient's value, bit for bit, for every piece of
 * cube-minus-ball and of the three balls (min of three spheres) and the gyroid ball (sin, cos
 * through the trig memo), at points on and off each piece's own region. */
Test(eval_piece, value_alone_is_the_gradient_pass_value)
{
    static const char *exprs[] = {
        CMB,
        "min((x - 0.6)^2 + y^2 + z^2 - 0.5, (x + 0.3)^2 + (y - 0.52)^2 + z^2 - 0.5, "
        "(x + 0.3)^2 + (y + 0.52)^2 + z^2 - 0.5)",
        "max(sin(3*x)*cos(3*y) + sin(3*y)*cos(3*z) + sin(3*z)*cos(3*x), x^2 + y^2 + z^2 - 1.96)",
        "min(abs(x) - 1, max(y, 0.5))"};
    for (size_t e = 0; e < sizeof exprs / sizeof *exprs; e++) {
        ism_tape *t = compile(exprs[e]);
        ism_eval_ws *ws = ism_eval_ws_new(t);
        int forced = 0; /* pairs whose piece at q is not f's own there: a kink really forced */
        for (int i = 0; i < 40; i++) { /* pieces from one point, values at another */
            double p[3] = {sin(1.3 * i) * 1.4, cos(0.7 * i) * 1.3, sin(0.37 * i + 1) * 1.2};
            double q[3] = {cos(0.9 * i) * 1.1, sin(1.9 * i) * 1.2, cos(0.53 * i) * 1.3};
            ism_piece pc = ism_eval_piece(t, ws, p[0], p[1], p[2]);
            cr_assert_neq(pc, ISM_PIECE_NONE);
            double g[3], v = ism_eval_piece_gradient(t, ws, pc, q[0], q[1], q[2], g);
            double w = ism_eval_piece_value(t, ws, pc, q[0], q[1], q[2]);
            cr_expect(memcmp(&v, &w, sizeof v) == 0, "%s, point %d: %.17g vs %.17g", exprs[e], i,
                      v, w);
            forced += w != ism_eval_point(t, ws, q[0], q[1], q[2]);
        }
        cr_expect_gt(forced, 0, "%s: every piece was f's own at q", exprs[e]);
        ism_eval_ws_free(ws);
        ism_tape_free(t);
    }
}

/* What each kink passes on each branch (workspace.h ism_kink_pass), against eval.h's meaning
 * of a piece's branches: 1 is min/max's first operand and abs's +a, 2 the second operand (a
 * register for the _RR forms, the constant for the _RC forms) and abs's -a. The one table
 * that shortening and the forced pieces both switch on. */
Test(eval_piece, kinks_pass_what_their_branch_names)
{
    const struct {
        int op;
        enum ism_kink_passed br1, br2;
    } rows[] = {
        {ISM_OP_MIN_RR, ISM_PASS_A, ISM_PASS_B},   {ISM_OP_MAX_RR, ISM_PASS_A, ISM_PASS_B},
        {ISM_OP_MIN_RC, ISM_PASS_A, ISM_PASS_IMM}, {ISM_OP_MAX_RC, ISM_PASS_A, ISM_PASS_IMM},
        {ISM_OP_ABS, ISM_PASS_A, ISM_PASS_NEG_A},
    };
    for (size_t i = 0; i < sizeof rows / sizeof *rows; i++) {
        ism_instr in = {.op = rows[i].op, .out = 3, .a = 1, .b = 2, .imm = 0.5};
        cr_expect(ism_op_is_kink(in.op), "op %d", in.op);
        cr_expect_eq(ism_kink_pass(&in, 1), rows[i].br1, "op %d branch 1", in.op);
        cr_expect_eq(ism_kink_pass(&in, 2), rows[i].br2, "op %d branch 2", in.op);
    }
}
