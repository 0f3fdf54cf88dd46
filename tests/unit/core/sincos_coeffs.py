#!/usr/bin/env python3
"""sincos_coeffs.py — derives core/eval/sincos.h's constants and writes core/eval/sincos_table.h,
with mpmath alone (no libm value is used):

  - the four-part split of pi/128 (Cody & Waite): Q1, Q2 and Q3 of SPLIT_BITS significant bits,
    so that j Q1, j Q2 and j Q3 are exact doubles for |j| < 2^(53 - SPLIT_BITS), Q4 the rest
    rounded;
  - 128/pi rounded;
  - the table: sin and cos of i pi/128, i = 0 .. 255, each as a double hi (rounded) and the
    double lo nearest the rest (hi + lo within 2^-106 relative of the value; 0 exactly where
    the value is 0), and each as g + d: g the integer nearest it (-1, 0 or 1), d the double
    nearest the rest;
  - the polynomials of sin r and cos r on |r| <= pi/256 (Taylor: their truncation error there,
    printed below, is far under a double's rounding).

python3 tests/unit/core/sincos_coeffs.py [--write | --check] (from any directory)
prints what it derives; --write rewrites core/eval/sincos_table.h: the constants as #defines,
SC_SPLIT_BITS and SC_128_PI_BITS among them, and the table — sincos.h holds no copy of either;
--check writes nothing and exits 1, showing the difference, when the file is not what --write
would write (a hand edit, or a change here not followed by --write): unit_proto's
generated_files/sincos_table_is_its_generators_output runs it."""
import difflib
import os
import sys

import mpmath as mp

mp.mp.dps = 80
SPLIT_BITS = 30     # j Q1, j Q2, j Q3 exact for 53 - SPLIT_BITS bits of j; sincos.h asserts its
                    # ISM_SINCOS_LIMIT_BITS + SC_128_PI_BITS fit them
N = 256             # table entries over a whole turn
R = mp.pi / N       # |r| <= pi/256 (plus a rounding's margin)


def split(v):
    parts = []
    rest = v
    for _ in range(3):
        e = mp.floor(mp.log(abs(rest), 2))
        scale = mp.mpf(2) ** (SPLIT_BITS - 1 - e)
        p = mp.floor(rest * scale) / scale  # rest truncated to SPLIT_BITS significant bits
        parts.append(p)
        rest -= p
    parts.append(mp.mpf(float(rest)))
    return parts, v - sum(parts)


def hi_lo(v):
    hi = float(v)
    return hi, float(v - mp.mpf(hi))


def constants():
    """The #define lines of the split, 128/pi and the polynomials' coefficients, with what the
    split misses and what the dropped Taylor terms weigh (comments)."""
    parts, miss = split(mp.pi / 128)
    lines = ["/* |j| < 2^(53 - SC_SPLIT_BITS) keeps j Q1, j Q2 and j Q3 exact doubles */",
             "#define SC_SPLIT_BITS %d" % SPLIT_BITS,
             "/* pi/128 = Q1 + Q2 + Q3 + Q4 + %s */" % mp.nstr(miss, 3)]
    for i, p in enumerate(parts):
        lines.append("#define SC_Q%d %s /* %s */" % (i + 1, float(p).hex(), mp.nstr(p, 22)))
    lines.append("#define SC_128_PI %s" % float(128 / mp.pi).hex())
    # j = x 128/pi: |x| < 2^k gives |j| < 2^(k + SC_128_PI_BITS)
    bits = int(mp.ceil(mp.log(128 / mp.pi, 2)))
    lines.append("#define SC_128_PI_BITS %d /* 128/pi = %s < 2^%d */" % (
        bits, mp.nstr(128 / mp.pi, 6), bits))
    # Taylor coefficients, and what the dropped terms weigh at |r| = pi/256 (relative)
    r = R * mp.mpf("1.001")
    for name, c in (("S1", -mp.mpf(1) / 6), ("S2", mp.mpf(1) / 120), ("S3", -mp.mpf(1) / 5040),
                    ("C1", mp.mpf(1) / 24), ("C2", -mp.mpf(1) / 720)):
        lines.append("#define SC_%s %s /* %r */" % (name, float(c).hex(), float(c)))
    lines.append("/* sin: next term r^9/9! over sin r: %s; cos: r^8/8! over cos r: %s */" % (
        mp.nstr(r ** 9 / mp.factorial(9) / mp.sin(r), 3),
        mp.nstr(r ** 8 / mp.factorial(8) / mp.cos(r), 3)))
    return lines


TABLE_PATH = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..",
                          "core", "eval", "sincos_table.h")


def main():
    consts = constants()
    if "--check" not in sys.argv:
        print("\n".join(consts))
    rows = []
    for i in range(N):
        a = 2 * mp.pi * i / N
        s = mp.mpf(0) if i in (0, N // 2) else mp.sin(a)
        c = mp.mpf(0) if i in (N // 4, 3 * N // 4) else mp.cos(a)
        sh, sl = hi_lo(s)
        ch, cl = hi_lo(c)
        gs, gc = mp.nint(s), mp.nint(c)
        row = (sh, sl, ch, cl, float(gs), float(s - gs), float(gc), float(c - gc))
        rows.append("    {" + ", ".join(v.hex() for v in row) + "},")
    text = (TABLE_HEAD + "\n".join(consts) + "\n\n" + TABLE_ROWS + "\n".join(rows)
            + "\n};\n\n#endif\n")
    if "--write" in sys.argv:
        with open(TABLE_PATH, "w") as f:
            f.write(text)
        print("wrote core/eval/sincos_table.h")
    elif "--check" in sys.argv:
        with open(TABLE_PATH) as f:
            held = f.read()
        if held != text:
            sys.stdout.writelines(difflib.unified_diff(
                held.splitlines(True), text.splitlines(True),
                "core/eval/sincos_table.h", "sincos_coeffs.py --write"))
            sys.exit(1)
        print("core/eval/sincos_table.h is what --write writes")


TABLE_HEAD = """/* sincos_table.h — sincos.h's constants: the split of pi/128 (Cody & Waite), 128/pi and the
 * polynomials' coefficients; and sin and cos of a = i pi/128, i = 0 .. 255 (a whole turn),
 * each as hi + lo (hi the double nearest the value, lo the double nearest the rest; 0 exactly
 * where the value is 0) and as g + d (g the integer nearest the value, -1, 0 or 1, d the
 * double nearest the rest). Generated by tests/unit/core/sincos_coeffs.py --write (mpmath, 80
 * digits); do not edit. Read by sincos.h only. */
#ifndef ISM_SINCOS_TABLE_H
#define ISM_SINCOS_TABLE_H

"""
TABLE_ROWS = """/* {sin a hi, lo, cos a hi, lo, sin a g, d, cos a g, d}: one entry, 64 bytes, two AVX2 loads */
static const double ism_sincos_table[256][8] __attribute__((aligned(64))) = {
"""

if __name__ == "__main__":
    main()
