#!/usr/bin/python3
"""List the product functions longer than a limit (STYLE.md "Size": past ~150
lines a function is several things; split it into named phases).

Usage:
  scripts/long-functions.py [--limit N] [--root DIR] [--check]

Scans the .cxx and .h files of Solvers/, Filters/, Readers/, Apps/ and Plugin/
(the product code; Testing/ is not scanned) and prints one line per function
over the limit: length, file:line, name. A function's length counts the lines
from its signature to its closing brace. Lambdas and local classes count as
part of the function that contains them.

With --check it exits 1 when a function not in ALLOWED below is over the
limit (or a file cannot be read); an ALLOWED entry that no longer names a
long function is noted, to be removed. Registered in ctest as
Architecture.LongFunctions.

How it reads C++: comments, string and character literals are blanked, the
#else/#elif branches of preprocessor conditionals are dropped (the first
branch is kept, so braces stay balanced), and braces are matched. A brace at
namespace or class scope whose header has a parameter list opens a function
body; member initialisers written with braces (`x_{y}`) before the body are
recognised. A file whose braces do not balance is an error, not a silent skip.
"""
import argparse
import os
import re
import sys

DIRECTORIES = ("Solvers", "Filters", "Readers", "Apps", "Plugin")
EXTENSIONS = (".cxx", ".h")
LIMIT = 150

# Functions allowed over the limit for now, each owned by another piece of
# work (issue 30) that will shorten it. Key: the name as printed (a file that
# moves keeps its entry), or "path::name" for a name used in several files.
ALLOWED = {
}


def strip_code(text):
    """Blank comments, string/char literals and preprocessor lines, keeping
    newlines so line numbers stay right. Keeps only the first branch of each
    #if/#ifdef ... #else/#elif ... #endif."""
    out = []
    i, n = 0, len(text)
    at_line_start = True
    skip_depth = 0        # > 0 while inside a dropped #else/#elif branch
    cond_stack = []       # per open #if: True once its first branch ended
    while i < n:
        c = text[i]
        if at_line_start:
            j = i
            while j < n and text[j] in " \t":
                j += 1
            if j < n and text[j] == "#":
                # A whole preprocessor directive (with continuations).
                k = j
                while True:
                    e = text.find("\n", k)
                    if e == -1:
                        e = n
                    if e > 0 and text[e - 1] == "\\" and e < n:
                        k = e + 1
                        continue
                    break
                directive = text[j + 1:e].strip()
                word = re.match(r"\w*", directive).group(0)
                if word in ("if", "ifdef", "ifndef"):
                    cond_stack.append(False)
                    if skip_depth:
                        skip_depth += 1
                elif word in ("else", "elif"):
                    if skip_depth <= 1 and cond_stack:
                        if not cond_stack[-1]:
                            cond_stack[-1] = True
                            skip_depth = 1
                elif word == "endif":
                    if cond_stack:
                        cond_stack.pop()
                    if skip_depth:
                        skip_depth -= 1
                out.append("\n" * text.count("\n", i, e))
                i = e
                continue
            at_line_start = False
        if c == "\n":
            out.append("\n")
            at_line_start = True
            i += 1
            continue
        if skip_depth:
            out.append(" ")
            i += 1
            continue
        if text.startswith("//", i):
            e = text.find("\n", i)
            e = n if e == -1 else e
            i = e
            continue
        if text.startswith("/*", i):
            e = text.find("*/", i + 2)
            e = n if e == -1 else e + 2
            out.append("\n" * text.count("\n", i, e) or " ")
            i = e
            continue
        m = re.compile(r'R"([^(\s]*)\(').match(text, i)
        if m and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            end = text.find(")" + m.group(1) + '"', m.end())
            e = n if end == -1 else end + len(m.group(1)) + 2
            out.append('""' + "\n" * text.count("\n", i, e))
            i = e
            continue
        if c == '"' or (c == "'" and not (i > 0 and text[i - 1].isalnum())):
            # A digit separator (1'000) is not a character literal.
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            out.append(c + c)
            i = j + 1
            continue
        out.append(c)
        i += 1
    return "".join(out)


TEMPLATE_PREFIX = re.compile(r"^\s*template\s*<")


def drop_template_prefix(header):
    h = header.strip()
    while TEMPLATE_PREFIX.match(h):
        depth, k = 0, h.index("<")
        while k < len(h):
            if h[k] == "<":
                depth += 1
            elif h[k] == ">":
                depth -= 1
                if depth == 0:
                    break
            k += 1
        h = h[k + 1:].strip()
    return h


def function_name(header):
    """The name in a function header: the qualified identifier before the
    parameter list (the first '(' outside template brackets)."""
    h = drop_template_prefix(header)
    h = re.sub(r"\b(public|private|protected)\s*:(?!:)", " ", h)
    m = re.search(r"(operator\s*(\(\)|[^\s(]+))\s*\(", h)
    if m:
        start = m.start()
        prefix = re.search(r"([~\w:]*)$", h[:start]).group(1)
        return prefix + "operator" + m.group(1)[len("operator"):].strip()
    depth = 0
    for k, ch in enumerate(h):
        if ch == "<":
            depth += 1
        elif ch == ">":
            depth = max(0, depth - 1)
        elif ch == "(" and depth == 0:
            before = h[:k].rstrip()
            m = re.search(r"([~\w]+(?:\s*<[^<>]*>)?(?:\s*::\s*~?\w+)*)$", before)
            if m:
                return re.sub(r"\s+", "", m.group(1))
            break
    # A lambda bound to a name: `auto f = [...](...) {`.
    m = re.search(r"(\w+)\s*=\s*\[", h)
    if m:
        return m.group(1) + " (lambda)"
    return "?"


def classify(header):
    """What a '{' at namespace/class scope opens: 'namespace', 'type',
    'function' or 'other' (an initialiser)."""
    h = drop_template_prefix(header)
    h = re.sub(r"^(\s*(public|private|protected)\s*:(?!:))+", " ", h).strip()
    if re.match(r"^(inline\s+)?namespace\b", h) or re.match(r"^extern\b", h):
        return "namespace"
    if re.match(r"^(typedef\s+)?(class|struct|union|enum)\b", h):
        # `struct X f(...) {` returns a struct: a function.
        if not re.search(r"\)\s*(const|override|final|noexcept|\s)*$", h):
            return "type"
    if "(" in h and re.search(
            r"\)\s*(const|override|final|noexcept|mutable|volatile|&|&&|\s)*"
            r"(->\s*[\w:<>,\s*&]+)?$", h):
        return "function"
    if "(" in h and re.search(r"\)\s*(const|noexcept|\s)*:\s*[^:]", h):
        # A constructor with member initialisers ending in a `{`: its body.
        return "function"
    return "other"


def ctor_initialiser_brace(header):
    """True when a '{' continues a constructor's member initialiser list
    (`A::A(int y) : x_{y}` or `: x_(y), z_{w}`), i.e. is not the body."""
    h = header.rstrip()
    if not re.search(r"\)\s*(noexcept\s*)?:(?!:)", h):
        return False
    return bool(re.search(r"[\w>]$", h))


def scan(path, text):
    """Yield (name, start_line, end_line) for every outermost function body."""
    code = strip_code(text)
    line = 1
    header_start = None     # index where the current header began
    header = []
    stack = []              # entries: 'namespace' | 'type' | 'other' | 'init'
    func = None             # (name, start_line, depth) while inside a function
    i, n = 0, len(code)
    line_of = []
    # Precompute line numbers per index lazily via counting.
    newline_positions = [k for k, ch in enumerate(code) if ch == "\n"]

    import bisect

    def line_at(index):
        return bisect.bisect_right(newline_positions, index - 1) + 1

    header_text = ""
    header_begin = 0
    while i < n:
        c = code[i]
        if func is not None:
            if c == "{":
                func[2] += 1
            elif c == "}":
                func[2] -= 1
                if func[2] == 0:
                    yield func[0], func[1], line_at(i)
                    func = None
                    header_text, header_begin = "", i + 1
            i += 1
            continue
        if c == "{":
            in_init = stack and stack[-1] == "other"
            if ctor_initialiser_brace(header_text):
                stack.append("init")
                header_text += "{"
                i += 1
                continue
            kind = classify(header_text)
            if kind == "function" or (in_init and re.search(
                    r"\]\s*(\([^()]*\))?\s*(mutable\s*)?(->[^{]*)?$",
                    header_text)):
                text_before = header_text
                stripped_lead = len(text_before) - len(text_before.lstrip())
                start = line_at(header_begin + stripped_lead)
                func = [function_name(text_before), start, 1]
                i += 1
                continue
            stack.append(kind)
            header_text, header_begin = "", i + 1
            i += 1
            continue
        if c == "}":
            if not stack:
                raise SyntaxError(f"{path}:{line_at(i)}: unbalanced '}}'")
            kind = stack.pop()
            if kind == "init":
                header_text += "}"
            else:
                header_text, header_begin = "", i + 1
            i += 1
            continue
        if c == ";" and not (stack and stack[-1] == "init"):
            header_text, header_begin = "", i + 1
            i += 1
            continue
        if c == ":" and re.search(r"\b(public|private|protected)\s*$",
                                  header_text) and not code.startswith("::", i):
            header_text, header_begin = "", i + 1
            i += 1
            continue
        header_text += c
        i += 1
    if func is not None or stack:
        raise SyntaxError(f"{path}: unbalanced braces at end of file")


def product_files(root):
    for top in DIRECTORIES:
        base = os.path.join(root, top)
        for dirpath, dirnames, filenames in os.walk(base):
            dirnames.sort()
            for name in sorted(filenames):
                if name.endswith(EXTENSIONS):
                    yield os.path.join(dirpath, name)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--limit", type=int, default=LIMIT)
    parser.add_argument("--root", default=os.path.dirname(
        os.path.dirname(os.path.abspath(__file__))))
    parser.add_argument("--check", action="store_true",
                        help="fail on a long function not in the allow-list")
    args = parser.parse_args()

    rows = []
    errors = []
    for path in product_files(args.root):
        rel = os.path.relpath(path, args.root)
        with open(path, encoding="utf-8", errors="replace") as f:
            text = f.read()
        try:
            for name, start, end in scan(rel, text):
                length = end - start + 1
                if length > args.limit:
                    rows.append((length, rel, start, name))
        except SyntaxError as e:
            errors.append(str(e))
    rows.sort(key=lambda r: (-r[0], r[1], r[2]))
    def allowed_key(rel, name):
        for key in (f"{rel}::{name}", name):
            if key in ALLOWED:
                return key
        return None

    for length, rel, start, name in rows:
        key = allowed_key(rel, name)
        mark = "  (allowed: " + ALLOWED[key] + ")" if key else ""
        print(f"{length:5d}  {rel}:{start}  {name}{mark}")
    print(f"{len(rows)} functions over {args.limit} lines"
          f" ({sum(1 for r in rows if r[0] > 200)} over 200,"
          f" {sum(1 for r in rows if r[0] > 300)} over 300,"
          f" {sum(1 for r in rows if r[0] > 600)} over 600)")
    for e in errors:
        print("error: " + e, file=sys.stderr)
    if not args.check:
        return 1 if errors else 0
    found = {allowed_key(r[1], r[3]) for r in rows}
    failed = bool(errors)
    for length, rel, start, name in rows:
        if not allowed_key(rel, name):
            print(f"FAIL: {rel}:{start} {name} is {length} lines"
                  f" (limit {args.limit}): split it into named phases",
                  file=sys.stderr)
            failed = True
    for key in sorted(set(ALLOWED) - found):
        # Not a failure: the owner's shortened function lands before the
        # allow-list is tidied.
        print(f"note: allow-list entry {key} is no longer over {args.limit}"
              " lines (or was renamed): remove it")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
