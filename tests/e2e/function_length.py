#!/usr/bin/env python3
"""Function length: no function defined in the given folders is longer than a limit (issue 13: the mapper's
stages stay readable, none over 150 lines).

  function_length.py [--max-lines N] [--list] DIR_OR_FILE...

A function's length is its physical lines from the first line of its signature to its closing brace. The
C++ is read as text: comments, string and character literals (raw strings too) and preprocessor lines are
blanked first, so braces inside them do not count; then every `{` is classified by the scope it opens
(namespace, class, function, other: an initialiser, a member's brace-initialiser in a constructor's list).
Lambdas and local classes count as part of the function around them. Exit 1 listing each offender as
FILE:LINE: NAME is N lines (max M); --list prints every function with its length instead (longest first).
"""
import argparse
import os
import re
import sys

SOURCE_ENDINGS = (".cc", ".cpp", ".cxx", ".h", ".hpp")


def blank_code(text):
    """Comments, literals and preprocessor lines replaced by spaces (newlines kept, so lines still count)."""
    out = []
    i, n = 0, len(text)
    line_start = True
    while i < n:
        c = text[i]
        if line_start and c in " \t":
            out.append(c)
            i += 1
            continue
        if line_start and c == "#":  # preprocessor line, with backslash continuations
            while i < n and text[i] != "\n":
                if text[i] == "\\" and i + 1 < n and text[i + 1] == "\n":
                    out.append("  \n")
                    i += 2
                    continue
                out.append(" ")
                i += 1
            continue
        line_start = False
        if text.startswith("//", i):
            while i < n and text[i] != "\n":
                out.append(" ")
                i += 1
            continue
        if text.startswith("/*", i):
            end = text.find("*/", i + 2)
            end = n if end < 0 else end + 2
            out.append(re.sub(r"[^\n]", " ", text[i:end]))
            i = end
            continue
        raw = re.match(r'(?:u8|u|U|L)?R"([^()\\ ]{0,16})\(', text[i:i + 24])
        if raw and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            close = ")" + raw.group(1) + '"'
            end = text.find(close, i + raw.end())
            end = n if end < 0 else end + len(close)
            out.append('"' + re.sub(r"[^\n]", " ", text[i + 1:end - 1]) + '"')
            i = end
            continue
        if c in "\"'":
            # A digit separator (1'000'000) is not a character literal.
            if c == "'" and i > 0 and text[i - 1].isalnum() and i + 1 < n and text[i + 1].isalnum():
                out.append(" ")
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            out.append(c + " " * (min(j, n) - i - 1) + (c if j < n else ""))
            i = j + 1
            continue
        if c == "\n":
            line_start = True
        out.append(c)
        i += 1
    return "".join(out)


def function_name(statement):
    """The qualified name before the parameter list of a function's signature."""
    depth = 0
    for k, ch in enumerate(statement):
        if ch == "(" and depth == 0:
            m = re.search(r"((?:[A-Za-z_]\w*\s*::\s*)*~?[A-Za-z_]\w*(?:\s*<[^()]*>)?|operator\s*[^\s(]+)\s*$",
                          statement[:k])
            if m:
                return re.sub(r"\s+", "", m.group(1))
            return statement[:k].split()[-1] if statement[:k].split() else "?"
        if ch == "<":
            depth += 0  # templates do not nest parentheses in signatures we care about
    return "?"


def is_member_initialiser(statement):
    """`Foo::Foo(int a) : x_{a}` — the `{` about to open belongs to a member of a constructor's list."""
    close = statement.rfind(")")
    if close < 0:
        return False
    # A top-level ':' after the parameter list (not '::'), and an identifier or '>' right before the brace.
    tail = statement[statement.find(")"):]
    if not re.search(r"\)\s*(?:const\s*|noexcept\s*|override\s*)*:(?!:)", tail):
        return False
    return bool(re.search(r"[\w>]\s*$", statement)) and not re.search(r"\)\s*$", statement)


def functions(text):
    """Yields (name, first_line, last_line) of each function defined at namespace or class scope."""
    code = blank_code(text)
    line = 1
    stack = []  # kinds of open scopes: 'ns', 'class', 'func', 'other'
    statement, statement_line = "", None
    saved = []  # statements interrupted by a member initialiser's braces
    func_start = []  # (name, first_line) of the open functions (outermost only)
    for ch in code:
        if ch == "\n":
            line += 1
        inside_function = "func" in stack
        if inside_function:
            if ch == "{":
                stack.append("other")
            elif ch == "}":
                kind = stack.pop()
                if kind == "func":
                    name, first = func_start.pop()
                    yield name, first, line
                    statement, statement_line = "", None
            continue
        if ch == "{":
            s = statement
            if re.search(r"\bnamespace\b|\bextern\s*\"", s) and "(" not in s:
                stack.append("ns")
            elif re.search(r"\b(class|struct|union|enum)\b", s) and "(" not in s.split("=")[0]:
                stack.append("class")
            elif "(" in s and is_member_initialiser(s):
                stack.append("init")
                saved.append((statement, statement_line))
                statement, statement_line = "", None
                continue
            elif "(" in s and "=" not in s.split("(")[0]:
                stack.append("func")
                func_start.append((function_name(s), statement_line or line))
            else:
                stack.append("other")
            statement, statement_line = "", None
        elif ch == "}":
            kind = stack.pop() if stack else "ns"
            if kind == "init":
                statement, statement_line = saved.pop()
                statement += "{}"
                continue
            statement, statement_line = "", None
        elif ch == ";" and (not stack or stack[-1] in ("ns", "class")):
            statement, statement_line = "", None
        elif ch == ":" and (not stack or stack[-1] == "class") and re.search(
                r"\b(public|private|protected)\s*$", statement):
            statement, statement_line = "", None
        else:
            if statement_line is None and not ch.isspace():
                statement_line = line
            if stack and stack[-1] == "other":
                continue
            statement += ch


def source_files(paths):
    for p in paths:
        if os.path.isfile(p):
            yield p
            continue
        for root, _, names in os.walk(p):
            for name in sorted(names):
                if name.endswith(SOURCE_ENDINGS):
                    yield os.path.join(root, name)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--max-lines", type=int, default=150)
    parser.add_argument("--list", action="store_true")
    parser.add_argument("paths", nargs="+")
    args = parser.parse_args()
    found, too_long = [], []
    for path in source_files(args.paths):
        with open(path, encoding="utf-8", errors="replace") as f:
            text = f.read()
        for name, first, last in functions(text):
            length = last - first + 1
            found.append((length, path, first, name))
            if length > args.max_lines:
                too_long.append((path, first, name, length))
    if args.list:
        for length, path, first, name in sorted(found, reverse=True):
            print(f"{length:5d} {path}:{first}: {name}")
        return 0
    if not found:
        print("function_length: no function found in " + " ".join(args.paths), file=sys.stderr)
        return 1
    for path, first, name, length in too_long:
        print(f"{path}:{first}: {name} is {length} lines (max {args.max_lines})")
    longest = max(found)
    print(f"function_length: {len(found)} functions, longest {longest[0]} lines ({longest[3]}, "
          f"{longest[1]}:{longest[2]}); {'FAIL' if too_long else 'PASS'}")
    return 1 if too_long else 0


if __name__ == "__main__":
    sys.exit(main())
