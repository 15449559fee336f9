#!/usr/bin/env python3
"""Check the links between the Markdown documents (README.md, Documentation/**.md)
and the section references of the sources.

Usage: /usr/bin/python3 scripts/check_doc_links.py [REPO_ROOT]

Checks, and prints one line per problem (exit status 1 if any):
1. every Markdown link [text](target) to a relative path resolves (images included),
   and a #anchor names a heading of the target;
2. every mention of a document by name (`Performance.md`, `Documentation/Solvers.md`,
   `Notes/Performance.md`) names a file that exists;
3. every section reference of the form `Name.md, "Section"` (also `Name.md "Section"`
   and `Name.md ("Section"`), in the documents and in the C++/Python/CMake sources,
   names a heading of that document or a bold paragraph title (`**Section.**`); the
   quote may wrap over a line break (and a comment marker).
"""
import os
import re
import sys

ROOT = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else
                       os.path.join(os.path.dirname(__file__), ".."))
DOC = os.path.join(ROOT, "Documentation")
# Documents that live outside the repository (the project's shared brief).
EXTERNAL = {"SPEC.md", "STYLE.md"}
SOURCE_DIRS = ["Apps", "Filters", "Solvers", "Readers", "Plugin", "Python", "Testing",
               "scripts", "Documentation/examples"]
SOURCE_EXT = (".cxx", ".h", ".py", ".txt", ".cmake", ".xml", ".sh", ".supp")


def markdown_files():
    files = [os.path.join(ROOT, "README.md")]
    for d, _, names in os.walk(DOC):
        files += [os.path.join(d, n) for n in names if n.endswith(".md")]
    return sorted(files)


def slug(heading):
    s = heading.strip().lower()
    s = re.sub(r"[^\w\- ]", "", s)
    return s.replace(" ", "-")


def titles(path):
    """Headings and bold paragraph titles of a Markdown file, normalised."""
    out = []
    for line in open(path, encoding="utf-8"):
        m = re.match(r"#+\s+(.*)", line)
        if m:
            out.append(norm(m.group(1)))
        for b in re.findall(r"\*\*([^*]+)\*\*", line):
            out.append(norm(b))
        for b in re.findall(r"(?:^|\s)\*([^*]+)\*", line):
            out.append(norm(b))
    return out


def norm(text):
    text = text.replace("`", "").replace("*", "")
    return re.sub(r"\s+", " ", text).strip().rstrip(".:").lower()


def resolve_doc(name, from_dir):
    """A mentioned document name -> path, or None."""
    # A bare name is a manual (Documentation/X.md), also from Notes/, whose files
    # share the manuals' names; a path is relative to the file, the repository
    # or Documentation/.
    if "/" not in name:
        cands = [os.path.join(DOC, name), os.path.join(ROOT, name), os.path.join(from_dir, name)]
    else:
        cands = [os.path.join(from_dir, name), os.path.join(ROOT, name), os.path.join(DOC, name)]
    for c in cands:
        if os.path.isfile(c):
            return os.path.normpath(c)
    return None


def main():
    problems = []
    docs = markdown_files()
    title_cache = {}

    def has_title(path, section):
        if path not in title_cache:
            title_cache[path] = titles(path)
        s = norm(section)
        return any(t.startswith(s) or s.startswith(t) and len(t) > 8 for t in title_cache[path])

    name_re = re.compile(r"((?:\.\./)?(?:Documentation/)?(?:Notes/)?[A-Z][A-Za-z0-9]*\.md)")
    ref_re = re.compile(
        r"((?:\.\./)?(?:Documentation/)?(?:Notes/)?[A-Z][A-Za-z0-9]*\.md)\)?,?\s*\(?"
        r"\"([^\"]+)\"")

    for path in docs:
        text = open(path, encoding="utf-8").read()
        rel = os.path.relpath(path, ROOT)
        here = os.path.dirname(path)
        for m in re.finditer(r"\]\(([^)\s]+)\)", text):
            target = m.group(1)
            if re.match(r"[a-z]+://", target) or target.startswith("mailto:"):
                continue
            file_part, _, anchor = target.partition("#")
            dest = os.path.normpath(os.path.join(here, file_part)) if file_part else path
            if not os.path.exists(dest):
                problems.append(f"{rel}: link to {target}: no such file")
            elif anchor and dest.endswith(".md"):
                heads = [slug(l.lstrip("#")) for l in open(dest, encoding="utf-8")
                         if l.startswith("#")]
                if anchor not in heads:
                    problems.append(f"{rel}: link to {target}: no such heading")
        check_text(rel, here, text, name_re, ref_re, has_title, problems)

    for d in SOURCE_DIRS:
        for dirpath, _, names in os.walk(os.path.join(ROOT, d)):
            for n in names:
                if not n.endswith(SOURCE_EXT) and n != "CMakeLists.txt":
                    continue
                p = os.path.join(dirpath, n)
                if os.path.abspath(p) == os.path.abspath(__file__):
                    continue
                try:
                    text = open(p, encoding="utf-8").read()
                except UnicodeDecodeError:
                    continue
                # Join comment continuations so that a quote may wrap.
                text = re.sub(r"\n\s*(//|#|\*)\s?", "\n", text)
                check_text(os.path.relpath(p, ROOT), DOC, text, name_re, ref_re,
                           has_title, problems, sources=True)

    for p in problems:
        print(p)
    print(f"{len(problems)} problem(s) in {len(docs)} documents and the sources")
    return 1 if problems else 0


def check_text(rel, here, text, name_re, ref_re, has_title, problems, sources=False):
    flat = re.sub(r"\s+", " ", text)
    for m in name_re.finditer(text):
        name = m.group(1)
        if os.path.basename(name) in EXTERNAL or name in ("README.md",) and sources:
            continue
        if resolve_doc(name, here) is None:
            problems.append(f"{rel}: mentions {name}: no such document")
    for m in ref_re.finditer(flat):
        name, section = m.group(1), m.group(2)
        if os.path.basename(name) in EXTERNAL or re.search(r"[;{}()<>=]|->", section):
            continue  # not a section title: a string of code
        dest = resolve_doc(name, here)
        if dest is None or not dest.endswith(".md"):
            continue
        if not has_title(dest, section):
            problems.append(f'{rel}: {name}, "{section}": no such section')


if __name__ == "__main__":
    sys.exit(main())
