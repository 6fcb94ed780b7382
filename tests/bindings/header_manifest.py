#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Reads the public headers and writes a C program that prints the manifest of the C API.

usage: header_manifest.py OUT.c HEADER...

The manifest lists every MICA_API function (name, return and parameter types with their sizes),
every public struct (size, alignment, and each field's offset and size), every scalar and
callback typedef, and every MICA_* integer constant. Names and types come from the header
text; sizes, offsets and constant values come from the compiler, so they are what a C caller
gets. The program prints JSON (`OUT json`) or a tab-separated form (`OUT tsv`) for languages
without a JSON reader (LuaJIT, C#):

  function  NAME  RETURN_CLASS  RETURN_SIZE  PARAM_COUNT
  param     FUNCTION  INDEX  NAME  CLASS  SIZE
  struct    NAME  SIZE  ALIGN  FIELD_COUNT
  field     STRUCT  NAME  OFFSET  SIZE  CLASS  COUNT
  typedef   NAME  SIZE  CLASS
  callback  NAME  PARAM_COUNT
  constant  NAME  VALUE

CLASS is one of int, uint, float, ptr, char, struct, void; COUNT is the number of elements of
an array field (1 for a scalar).
"""
import re
import sys


def strip_comments(text):
    # Block comments become one space so tokens on either side stay apart; line comments go too.
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    return re.sub(r"//[^\n]*", "", text)


def split_top(text, sep=","):
    # Splits on `sep` outside parentheses and brackets.
    parts, depth, cur = [], 0, []
    for ch in text:
        if ch in "([":
            depth += 1
        elif ch in ")]":
            depth -= 1
        if ch == sep and depth == 0:
            parts.append("".join(cur))
            cur = []
        else:
            cur.append(ch)
    parts.append("".join(cur))
    return [p.strip() for p in parts if p.strip()]


# Typedef names of the headers: scalar ones map to their base type, the others to a class.
TYPEDEF_BASES = {}


def classify(type_text):
    """The ABI class of a C type as written in the header (arrays and pointers are ptr)."""
    t = " ".join(type_text.replace("const", " ").split())
    if "*" in t or "[" in t:
        return "ptr"
    if t in TYPEDEF_BASES:
        return classify(TYPEDEF_BASES[t]) if TYPEDEF_BASES[t] not in ("ptr", "struct") else TYPEDEF_BASES[t]
    if t == "void":
        return "void"
    if t in ("double", "float"):
        return "float"
    if t == "char":
        return "char"
    if re.fullmatch(r"uint(8|16|32|64)_t|size_t", t):
        return "uint"
    if re.fullmatch(r"int(8|16|32|64)_t", t):
        return "int"
    # A new type in the header must be taught here rather than guessed.
    raise ValueError("cannot classify C type '%s'" % type_text)


def parse_param(text):
    """(name, type) of one parameter; array parameters decay to pointers."""
    fp = re.match(r"(.*)\(\s*\*\s*(\w+)\s*\)\s*\((.*)\)$", text, re.S)
    if fp:
        return fp.group(2), "void*"
    m = re.match(r"(.*?)(\w+)\s*((?:\[[^\]]*\]\s*)*)$", text, re.S)
    if not m or not m.group(1).strip():
        raise ValueError("cannot parse parameter '%s'" % text)
    base, name, dims = m.group(1).strip(), m.group(2), m.group(3).strip()
    ctype = base + ("*" if dims else "")
    return name, " ".join(ctype.split())


def parse_headers(paths):
    functions, structs, typedefs, callbacks, constants = [], [], [], [], []
    seen_const = set()
    for path in paths:
        with open(path) as f:
            raw = f.read()
        text = strip_comments(raw.replace("\\\n", " "))
        for m in re.finditer(r"^\s*#\s*define\s+(MICA_\w+)(\(?)[ \t]*([^\n]*)$", text, re.M):
            name, paren, value = m.group(1), m.group(2), m.group(3).strip()
            # Skip the export macro, include guards and function-like macros.
            if paren or not value or name == "MICA_API" or name in seen_const:
                continue
            seen_const.add(name)
            constants.append(name)
        # Declarations only: drop preprocessor lines and the bodies of static inline functions.
        decl = re.sub(r"^\s*#[^\n]*$", "", text, flags=re.M)
        decl = re.sub(r"static\s+inline[^{;]*\{[^}]*\}", "", decl)
        for m in re.finditer(r"\bMICA_API\b([^;]*);", decl):
            proto = " ".join(m.group(1).split())
            head, _, params = proto.partition("(")
            params = params[: params.rindex(")")]
            hm = re.match(r"(.*?)(\w+)\s*$", head)
            ret, name = hm.group(1).strip(), hm.group(2)
            plist = [] if params.strip() in ("", "void") else split_top(params)
            functions.append((name, ret, [parse_param(p) for p in plist]))
        for m in re.finditer(r"typedef\s+struct\s+(\w+)\s*\{(.*?)\}\s*(\w+)\s*;", decl, re.S):
            name, body = m.group(3), m.group(2)
            fields = []
            for fdecl in [d.strip() for d in body.split(";") if d.strip()]:
                fdecl = " ".join(fdecl.split())
                fp = re.match(r"(.*)\(\s*\*\s*(\w+)\s*\)\s*\((.*)\)$", fdecl)
                if fp:
                    fields.append((fp.group(2), "void*", []))
                    continue
                fm = re.match(r"(.*?)(\w+)\s*((?:\[[^\]]*\]\s*)*)$", fdecl)
                dims = re.findall(r"\[([^\]]*)\]", fm.group(3))
                fields.append((fm.group(2), fm.group(1).strip(), dims))
            structs.append((name, fields))
            TYPEDEF_BASES[name] = "struct"
        for m in re.finditer(r"typedef\s+([\w\s]+?)\s+(\w+)\s*;", decl):
            if not m.group(1).startswith("struct"):
                typedefs.append((m.group(2), m.group(1)))
                TYPEDEF_BASES[m.group(2)] = m.group(1)
        for m in re.finditer(r"typedef\s+[\w\s\*]+\(\s*\*\s*(\w+)\s*\)\s*\(([^)]*)\)\s*;", decl):
            args = m.group(2).strip()
            callbacks.append((m.group(1), 0 if args in ("", "void") else len(split_top(args))))
            TYPEDEF_BASES[m.group(1)] = "ptr"
    return functions, structs, typedefs, callbacks, constants


def c_string(s):
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


def generate_c(paths, functions, structs, typedefs, callbacks, constants):
    out = []
    w = out.append
    w("/* Generated by tests/bindings/header_manifest.py from the public headers: do not edit. */")
    w("#include <stddef.h>\n#include <stdio.h>\n#include <string.h>")
    for p in paths:
        w('#include "%s"' % p)
    w("""
static int json;
static int first;
/* Opens a JSON list; in TSV mode lists are implicit. */
static void list_begin(const char* key) { if (json) printf("%s\\n  \\"%s\\": [", first ? "" : ",", key); first = 0; }
static void list_end(void) { if (json) printf("\\n  ]"); }
static void item(int index) { if (json) printf("%s\\n    ", index ? "," : ""); }
""")
    w("int main(int argc, char** argv) {")
    w('  json = !(argc > 1 && strcmp(argv[1], "tsv") == 0);')
    w("  first = 1;")
    w('  if (json) printf("{");')

    w('  list_begin("functions");')
    for i, (name, ret, params) in enumerate(functions):
        rclass = classify(ret)
        rsize = "0" if rclass == "void" else "sizeof(%s)" % ret
        w("  item(%d);" % i)
        w("  if (json) {")
        w('    printf("{\\"name\\": \\"%s\\", \\"return\\": {\\"type\\": %s, \\"class\\": \\"%s\\", \\"size\\": %%d}, \\"params\\": [", (int)%s);'
          % (name, c_string(c_string(ret))[1:-1], rclass, rsize))
        for j, (pname, ptype) in enumerate(params):
            w('    printf("%s{\\"name\\": \\"%s\\", \\"type\\": %s, \\"class\\": \\"%s\\", \\"size\\": %%d}", (int)sizeof(%s));'
              % (", " if j else "", pname, c_string(c_string(ptype))[1:-1], classify(ptype), ptype))
        w('    printf("]}");')
        w("  } else {")
        w('    printf("function\\t%s\\t%s\\t%%d\\t%d\\n", (int)%s);' % (name, rclass, len(params), rsize))
        for j, (pname, ptype) in enumerate(params):
            w('    printf("param\\t%s\\t%d\\t%s\\t%s\\t%%d\\n", (int)sizeof(%s));' % (name, j, pname, classify(ptype), ptype))
        w("  }")
    w("  list_end();")

    w('  list_begin("structs");')
    for i, (name, fields) in enumerate(structs):
        w("  item(%d);" % i)
        w("  if (json) {")
        w('    printf("{\\"name\\": \\"%s\\", \\"size\\": %%d, \\"align\\": %%d, \\"fields\\": [", (int)sizeof(%s), (int)_Alignof(%s));'
          % (name, name, name))
        for j, (fname, ftype, dims) in enumerate(fields):
            count = "*".join(dims) if dims else "1"
            w('    printf("%s{\\"name\\": \\"%s\\", \\"type\\": %s, \\"class\\": \\"%s\\", \\"offset\\": %%d, \\"size\\": %%d, \\"count\\": %%d}", (int)offsetof(%s, %s), (int)sizeof(((%s*)0)->%s), (int)(%s));'
              % (", " if j else "", fname, c_string(c_string(ftype))[1:-1], classify(ftype), name, fname, name, fname, count))
        w('    printf("]}");')
        w("  } else {")
        w('    printf("struct\\t%s\\t%%d\\t%%d\\t%d\\n", (int)sizeof(%s), (int)_Alignof(%s));' % (name, len(fields), name, name))
        for fname, ftype, dims in fields:
            count = "*".join(dims) if dims else "1"
            w('    printf("field\\t%s\\t%s\\t%%d\\t%%d\\t%s\\t%%d\\n", (int)offsetof(%s, %s), (int)sizeof(((%s*)0)->%s), (int)(%s));'
              % (name, fname, classify(ftype), name, fname, name, fname, count))
        w("  }")
    w("  list_end();")

    w('  list_begin("typedefs");')
    for i, (name, base) in enumerate(typedefs):
        w("  item(%d);" % i)
        w('  if (json) printf("{\\"name\\": \\"%s\\", \\"class\\": \\"%s\\", \\"size\\": %%d}", (int)sizeof(%s));'
          % (name, classify(base), name))
        w('  else printf("typedef\\t%s\\t%%d\\t%s\\n", (int)sizeof(%s));' % (name, classify(base), name))
    w("  list_end();")

    w('  list_begin("callbacks");')
    for i, (name, argc) in enumerate(callbacks):
        w("  item(%d);" % i)
        w('  if (json) printf("{\\"name\\": \\"%s\\", \\"param_count\\": %d}");' % (name, argc))
        w('  else printf("callback\\t%s\\t%d\\n");' % (name, argc))
    w("  list_end();")

    w('  list_begin("constants");')
    for i, name in enumerate(constants):
        w("  item(%d);" % i)
        w('  if (json) printf("{\\"name\\": \\"%s\\", \\"value\\": %%lld}", (long long)(%s));' % (name, name))
        w('  else printf("constant\\t%s\\t%%lld\\n", (long long)(%s));' % (name, name))
    w("  list_end();")

    w('  if (json) printf("\\n}\\n");')
    w("  return 0;")
    w("}")
    return "\n".join(out) + "\n"


def main(argv):
    if len(argv) < 3:
        sys.stderr.write("usage: header_manifest.py OUT.c HEADER...\n")
        return 2
    out, paths = argv[1], argv[2:]
    parsed = parse_headers(paths)
    if not parsed[0]:
        sys.stderr.write("header_manifest.py: no MICA_API function found in %s\n" % " ".join(paths))
        return 1
    code = generate_c(paths, *parsed)
    with open(out, "w") as f:
        f.write(code)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
