// expr.js — the viewer's copy of the expression grammar (core/expr/parser.c), used to point at
// a mistake before anything is sent and to find the free names that become parameters. The
// server stays the authority: when it disagrees, its 400 (with line and column) is shown.
//
//   source  := { "let" NAME "=" expr (";" | newline) } expr
//   expr    := term { ("+" | "-") term }
//   term    := unary { ("*" | "/") unary }
//   unary   := ("-" | "+") unary | power
//   power   := primary [ "^" expo ]          expo: a constant integer, |n| <= 64
//   expo    := ("-" | "+") expo | power
//   primary := NUMBER | NAME | NAME "(" args ")" | "(" expr ")"
//
// Lines and columns are 1-based and count characters as the server counts bytes (the same for
// ASCII; anything else is an error at its first character on both sides).

export const FUNCTIONS = {
  sqrt: [1, 1], sin: [1, 1], cos: [1, 1], tan: [1, 1], exp: [1, 1], log: [1, 1], abs: [1, 1],
  min: [2, Infinity], max: [2, Infinity], pow: [2, 2],
};
export const CONSTANTS = { pi: Math.PI, e: Math.E };
const VARIABLES = new Set(['x', 'y', 'z']);
const MAX_EXPONENT = 64;
const MAX_NAME = 63;

class ExprError extends Error {
  constructor(tok, message) {
    super(message);
    this.line = tok.line;
    this.column = tok.column;
  }
}

// ---- lexer ------------------------------------------------------------------------------

const isDigit = (c) => c >= '0' && c <= '9';
const isAlpha = (c) => (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z');
const isNameChar = (c) => isAlpha(c) || isDigit(c) || c === '_';
const SINGLES = { '+': 'PLUS', '-': 'MINUS', '*': 'STAR', '/': 'SLASH', '^': 'CARET',
  '(': 'LPAREN', ')': 'RPAREN', ',': 'COMMA', ';': 'SEMI', '=': 'ASSIGN' };

function tokenize(src) {
  const toks = [];
  let pos = 0, line = 1, column = 1;
  const advance = () => {
    if (src[pos] === '\n') { line++; column = 1; } else { column++; }
    pos++;
  };
  for (;;) {
    while (pos < src.length && ' \t\n\r'.includes(src[pos])) advance();
    const tok = { kind: 'END', line, column, text: '', endLine: line };
    if (pos >= src.length) { toks.push(tok); return toks; }
    const c = src[pos];
    if (isDigit(c) || (c === '.' && isDigit(src[pos + 1] || ''))) {
      let k = 0;
      const digits = (from) => { let d = 0; while (isDigit(src[pos + from + d] || '')) d++; return d; };
      k = digits(0);
      if (src[pos + k] === '.') k += 1 + digits(k + 1);
      if (src[pos + k] === 'e' || src[pos + k] === 'E') {
        let e = k + 1;
        if (src[pos + e] === '+' || src[pos + e] === '-') e++;
        const d = digits(e);
        if (d === 0) {
          throw new ExprError(tok, `malformed number '${src.slice(pos, pos + Math.min(e, 32))}': ` +
            'the exponent needs digits');
        }
        k = e + d;
      }
      const after = src[pos + k] || '';
      if (isAlpha(after) || after === '_' || after === '.') {
        throw new ExprError(tok, `malformed number '${src.slice(pos, pos + Math.min(k + 1, 32))}' ` +
          '(write 2*x, not 2x)');
      }
      tok.text = src.slice(pos, pos + k);
      if (k >= 64) throw new ExprError(tok, 'number is too long (at most 63 characters)');
      tok.number = Number(tok.text);
      if (!Number.isFinite(tok.number)) throw new ExprError(tok, `number ${tok.text} is too large`);
      tok.kind = 'NUM';
      for (let i = 0; i < k; i++) advance();
    } else if (isAlpha(c) || c === '_') {
      let k = 0;
      while (pos + k < src.length && isNameChar(src[pos + k])) k++;
      tok.text = src.slice(pos, pos + k);
      if (k > MAX_NAME) {
        throw new ExprError(tok, `name '${tok.text.slice(0, 16)}...' is too long (at most 63 characters)`);
      }
      tok.kind = 'NAME';
      for (let i = 0; i < k; i++) advance();
    } else if (SINGLES[c]) {
      tok.kind = SINGLES[c];
      tok.text = c;
      advance();
    } else {
      const code = src.charCodeAt(pos);
      const shown = code >= 0x21 && code < 0x7f ? `'${c}'` : 'a character outside ASCII';
      throw new ExprError(tok, `unexpected character ${shown}`);
    }
    tok.endLine = line;
    toks.push(tok);
  }
}

function describe(t) {
  if (t.kind === 'END') return 'the end of the expression';
  if (t.kind === 'NUM') return `number ${t.text.slice(0, 24)}`;
  if (t.kind === 'NAME') return `name '${t.text}'`;
  return `'${t.text}'`;
}

// ---- parser: each rule returns {v, g}: v the constant value of what it read (or null), g
// the same as GLSL (ES 3.0) source over vec3 p, for the clip cap's shader (glsl.js) --------

const K = (v) => ({ v, g: glslNumber(v) });
const N = (g) => ({ v: null, g });

// Largest magnitude written as a GLSL float literal (float's range ends at 3.4e38; a larger
// literal does not compile) and the smallest kept (below, a float is zero anyway).
const GLSL_FLOAT_MAX = 1e38;
const GLSL_FLOAT_MIN = 1e-37;

// A double as a GLSL float literal (always with a point or an exponent), clamped to float.
function glslNumber(v) {
  if (Number.isNaN(v) || Math.abs(v) < GLSL_FLOAT_MIN) return '0.0';
  if (Math.abs(v) > GLSL_FLOAT_MAX) return v > 0 ? '1e38' : '-1e38';
  const t = String(v);
  return /[.e]/.test(t) ? t : t + '.0';
}

class Parser {
  constructor(src, paramValues) {
    this.toks = tokenize(src);
    this.i = 0;
    this.paramValues = paramValues || {};
    this.lets = new Map();       // name -> {v, g} (g: the let's GLSL local)
    this.letCode = [];           // GLSL declarations of the lets, in order
    this.letOrder = [];
    this.free = [];              // free names in order of first use (the parameters)
    this.declared = new Set();   // every let name written anywhere (for "defined later")
    this.inLet = false;          // parsing the value of a let line
    this.openParens = 0;         // parentheses (groups and calls) open here
    for (let k = 0; k + 1 < this.toks.length; k++) {
      if (this.toks[k].kind === 'NAME' && this.toks[k].text === 'let' && this.toks[k + 1].kind === 'NAME') {
        this.declared.add(this.toks[k + 1].text);
      }
    }
  }
  get tok() { return this.toks[this.i]; }
  get prevEndLine() { return this.i > 0 ? this.toks[this.i - 1].endLine : 1; }
  next() { this.i++; }

  source() {
    if (this.tok.kind === 'END') throw new ExprError(this.tok, 'the expression is empty');
    while (this.tok.kind === 'NAME' && this.tok.text === 'let') {
      this.letStatement();
      if (this.tok.kind === 'END') {
        throw new ExprError(this.tok, 'expected the final expression after the lets');
      }
    }
    const f = this.expr();
    if (this.tok.kind !== 'END') this.trailing();
    return f;
  }

  letStatement() {
    this.next();
    const name = this.tok;
    if (name.kind !== 'NAME') throw new ExprError(name, `expected a name after 'let', found ${describe(name)}`);
    this.checkNewName(name);
    this.next();
    if (this.tok.kind !== 'ASSIGN') {
      throw new ExprError(this.tok, `expected '=' after 'let NAME', found ${describe(this.tok)}`);
    }
    this.next();
    this.inLet = true;
    const value = this.expr();
    this.inLet = false;
    const local = `l_${name.text}`;
    this.letCode.push(`float ${local} = ${value.g};`);
    this.lets.set(name.text, { v: value.v, g: value.v === null ? local : value.g });
    this.letOrder.push(name.text);
    if (this.tok.kind === 'SEMI') { this.next(); return; }
    if (this.tok.kind === 'END' || this.tok.line > this.prevEndLine) return;
    throw new ExprError(this.tok, `expected ';' or a new line after the let, found ${describe(this.tok)}`);
  }

  checkNewName(t) {
    const n = t.text;
    let msg = null;
    if (VARIABLES.has(n)) msg = `let '${n}' would shadow the variable ${n}`;
    else if (FUNCTIONS[n]) msg = `let '${n}' would shadow the function ${n}()`;
    else if (n in CONSTANTS) msg = `let '${n}' would shadow the constant ${n}`;
    else if (n === 'let') msg = "let name 'let' is a keyword";
    else if (this.lets.has(n)) msg = `let '${n}' is already defined as a let`;
    else if (this.free.includes(n)) msg = `let '${n}' is already defined as a parameter`;
    if (msg) throw new ExprError(t, msg);
  }

  trailing() {
    const t = this.tok;
    if (t.kind === 'NUM' || t.kind === 'NAME' || t.kind === 'LPAREN') {
      throw new ExprError(t, `expected an operator before ${describe(t)}`);
    }
    if (t.kind === 'ASSIGN') {
      throw new ExprError(t, "unexpected '=': write the surface as one expression f, meaning f = 0 " +
        '(e.g. x^2 + y^2 - 1)');
    }
    throw new ExprError(t, `unexpected ${describe(t)}`);
  }

  expr() {
    let l = this.term();
    while (this.tok.kind === 'PLUS' || this.tok.kind === 'MINUS') {
      const op = this.tok;
      this.next();
      const r = this.term();
      l = fold(op, l, r, (a, b) => (op.kind === 'PLUS' ? a + b : a - b), op.text);
    }
    return l;
  }

  term() {
    let l = this.unary();
    while (this.tok.kind === 'STAR' || this.tok.kind === 'SLASH') {
      const op = this.tok;
      this.next();
      if (op.kind === 'STAR' && this.tok.kind === 'STAR') throw new ExprError(op, 'use ^ for powers, not **');
      const r = this.unary();
      if (op.kind === 'SLASH' && r.v === 0) throw new ExprError(op, 'division by zero');
      l = fold(op, l, r, (a, b) => (op.kind === 'STAR' ? a * b : a / b), op.text);
    }
    return l;
  }

  unary() {
    const at = this.tok;
    if (at.kind !== 'MINUS' && at.kind !== 'PLUS') return this.power();
    this.next();
    const u = this.unary();
    if (at.kind !== 'MINUS') return u;
    return u.v !== null ? K(-u.v) : N(`(-${u.g})`);
  }

  exponent() {
    const at = this.tok;
    if (at.kind === 'MINUS' || at.kind === 'PLUS') {
      this.next();
      const e = this.exponent();
      if (at.kind !== 'MINUS') return e;
      return e.v !== null ? K(-e.v) : N(`(-${e.g})`);
    }
    return this.power();
  }

  power() {
    const base = this.primary();
    if (this.tok.kind !== 'CARET') return base;
    this.next();
    const at = this.tok;
    const e = this.exponent();
    return this.buildPower(base, e, at);
  }

  // base ^ e for a constant integer e ({v, g} both).
  buildPower(base, exp, at) {
    const e = exp.v;
    if (e === null) {
      throw new ExprError(at, 'bad exponent: ^ needs a constant integer (for other powers use pow(a, b))');
    }
    if (e !== Math.floor(e)) {
      throw new ExprError(at, `bad exponent ${fmt(e)}: ^ needs an integer (for other powers use pow(a, b) or sqrt)`);
    }
    if (Math.abs(e) > MAX_EXPONENT) throw new ExprError(at, `exponent ${e} is too large (limit ${MAX_EXPONENT})`);
    if (base.v !== null) {
      const v = checkFinite(at, Math.pow(base.v, e));
      if (v !== null) return K(v);
    }
    const g = e === 0 ? '1.0' : `ipow(${base.g}, ${Math.abs(e)})`;
    return N(e < 0 ? `(1.0 / ${g})` : g);
  }

  primary() {
    const at = this.tok;
    switch (at.kind) {
      case 'NUM':
        this.next();
        return K(at.number);
      case 'NAME':
        return this.name();
      case 'LPAREN': {
        this.next();
        this.openParens++;
        const v = this.expr();
        this.openParens--;
        if (this.tok.kind !== 'RPAREN') {
          throw new ExprError(this.tok, `expected ')' to close the '(' at line ${at.line}, col ${at.column}, ` +
            `found ${describe(this.tok)}`);
        }
        this.next();
        return v;
      }
      default:
        throw new ExprError(at, `expected a number, a name or '(', found ${describe(at)}`);
    }
  }

  name() {
    const t = this.tok;
    const n = t.text;
    this.next();
    // NAME ( is a call, except that a let's value ends with its line: a '(' starting the
    // next line begins the next statement (as in core/expr/parser.c).
    const nextStatement = this.inLet && this.openParens === 0 && this.tok.line > t.endLine;
    if (this.tok.kind === 'LPAREN' && !nextStatement) return this.call(t);
    if (VARIABLES.has(n)) return N(`p.${n}`);
    if (n in CONSTANTS) return K(CONSTANTS[n]);
    if (this.lets.has(n)) return this.lets.get(n);
    if (FUNCTIONS[n]) throw new ExprError(t, `'${n}' is a function: write ${n}(...)`);
    if (n === 'let') throw new ExprError(t, "'let' can only start a line before the final expression: let NAME = EXPR");
    if (this.declared.has(n)) {
      throw new ExprError(t, `unknown name '${n}' (a let can only use lets defined before it)`);
    }
    // Anything else is a parameter: the viewer gives it a slider and sends its value.
    if (!this.free.includes(n)) this.free.push(n);
    const v = this.paramValues[n];
    return typeof v === 'number' ? K(v) : N('0.0');
  }

  call(nameTok) {
    const n = nameTok.text;
    const arity = FUNCTIONS[n];
    if (!arity) {
      if (VARIABLES.has(n) || n in CONSTANTS || this.lets.has(n) || this.free.includes(n)) {
        throw new ExprError(nameTok, `'${n}' is not a function (write '*' to multiply)`);
      }
      throw new ExprError(nameTok, `unknown function '${n}'`);
    }
    const open = this.tok;
    this.next();
    this.openParens++;
    const args = [];
    let secondAt = this.tok;
    if (this.tok.kind !== 'RPAREN') {
      for (;;) {
        const argAt = this.tok;
        args.push(this.expr());
        if (args.length === 2) secondAt = argAt;
        if (this.tok.kind !== 'COMMA') break;
        this.next();
      }
    }
    this.openParens--;
    if (this.tok.kind !== 'RPAREN') {
      throw new ExprError(this.tok, `expected ',' or ')' in the call to ${n}( at col ${open.column}, ` +
        `found ${describe(this.tok)}`);
    }
    this.next();
    const [lo, hi] = arity;
    if (args.length < lo || args.length > hi) {
      if (hi === Infinity) throw new ExprError(nameTok, `'${n}' takes at least ${lo} arguments, got ${args.length}`);
      throw new ExprError(nameTok, `'${n}' takes ${lo} argument${lo === 1 ? '' : 's'}, got ${args.length}`);
    }
    if (n === 'pow') {
      const [a, b] = args;
      if (b.v !== null && b.v === Math.floor(b.v)) return this.buildPower(a, b, secondAt);
      const v = a.v === null || b.v === null ? null : checkFinite(nameTok, Math.pow(Math.max(a.v, 0), b.v));
      return v !== null ? K(v) : N(`pow(max(${a.g}, 0.0), ${b.g})`);
    }
    const f = { sqrt: Math.sqrt, sin: Math.sin, cos: Math.cos, tan: Math.tan, exp: Math.exp,
      log: Math.log, abs: Math.abs, min: Math.min, max: Math.max }[n];
    if (args.every((a) => a.v !== null)) {
      const v = checkFinite(nameTok, f(...args.map((a) => a.v)));
      if (v !== null) return K(v);
    }
    // min and max of more than two: nested (GLSL's take two)
    if (args.length === 1) return N(`${n}(${args[0].g})`);
    return N(args.map((a) => a.g).reduce((acc, g) => `${n}(${acc}, ${g})`));
  }
}

function fmt(v) { return String(Number(v.toPrecision(6))); }

// A folded constant that is not finite is left unfolded: the server decides what it means.
function checkFinite(at, v) {
  return Number.isFinite(v) ? v : null;
}

// a op b: folded when both are constants (and the result finite), else GLSL (op: + - * /).
function fold(op, a, b, f, glslOp) {
  const v = a.v === null || b.v === null ? null : checkFinite(op, f(a.v, b.v));
  return v !== null ? K(v) : N(`(${a.g} ${glslOp} ${b.g})`);
}

// Checks src. paramValues (name -> number) are folded like the server folds parameters, so an
// exponent written with a parameter is checked with its current value.
// Returns {ok: true, params: [free names], lets: [let names], glsl: {lets: [declarations],
// f: GLSL of f over vec3 p (parameters as their current values)}} or
// {ok: false, line, column, message}.
export function checkExpression(src, paramValues) {
  try {
    const p = new Parser(src, paramValues);
    const f = p.source();
    return { ok: true, params: p.free, lets: p.letOrder, glsl: { lets: p.letCode, f: f.g } };
  } catch (e) {
    if (e instanceof ExprError) return { ok: false, line: e.line, column: e.column, message: e.message };
    throw e;
  }
}

// The text of a preset as the editor shows it: its lets as `let` lines, then the expression.
export function presetSource(preset) {
  const lets = (preset.let || []).map(([name, src]) => `let ${name} = ${src};\n`).join('');
  return lets + preset.expr;
}
