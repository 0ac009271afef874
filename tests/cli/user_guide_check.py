#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Runs the shell examples of docs/user-guide.md, in order, in one scratch folder, and checks
that what the guide shows as their output is what they print.

- Every `ido ...` line of a ```sh block is run (a trailing backslash continues it; `make`
  lines are the build's own and are left out). `ido` is the tool under test; `../shared/data`
  is the shared scans' folder ($IDO_SHARED_DATA when set, as for the other tests), and a
  command that needs it is skipped when it is absent.
- A block whose info string names a file after its language (```json beam.json) is written
  to that file before the commands that follow it.
- Every command must exit 0. One that fails for a file a later example writes (the guide shows
  `ido info` on a surface before `ido segment` makes it) is run once more after all others.
- What the guide shows as output: a whole-line `# ...` comment right after a command, and a
  plain ``` block that follows a ```sh block with only blank lines between them (the output of
  that block's commands). Each shown line must match a printed line: the same words, and the
  same numbers as printed, except durations (a number followed by `s`), which depend on the
  machine.

- A ```python block is run with the module on --python-path (skipped without it): it must
  exit 0, and a `print(...)  # FIGURE` line must print FIGURE to the digits shown (the k-th
  such line, the k-th line printed).

Exit 0 when every check holds, 1 otherwise (each failure on one line).
"""
import argparse
import os
import re
import shlex
import subprocess
import sys
import tempfile

DURATION = re.compile(r"-?\d+(?:\.\d+)?\s*s\b")
NUMBER = re.compile(r"-?\d+(?:\.\d+)?(?:e[-+]?\d+)?")


def skeleton(line):
    """The line's words with durations dropped and every number replaced by '#'."""
    return " ".join(NUMBER.sub("#", DURATION.sub("", line)).split())


def numbers(line):
    return NUMBER.findall(DURATION.sub("", line))


def parse_guide(text):
    """[(commands, shown)]: each ```sh block's commands, each with the lines shown as its output."""
    blocks = []  # (info, lines, blank lines before it since the previous block ended)
    lines = text.splitlines()
    i, since = 0, []
    while i < len(lines):
        if lines[i].startswith("```"):
            info, body = lines[i][3:].strip(), []
            i += 1
            while i < len(lines) and not lines[i].startswith("```"):
                body.append(lines[i])
                i += 1
            blocks.append((info, body, all(not s.strip() for s in since)))
            since = []
        else:
            since.append(lines[i])
        i += 1
    examples = []
    for info, body, adjacent in blocks:
        words = info.split()
        if len(words) == 2 and words[0] != "sh":
            examples.append({"commands": [], "shown": [], "file": (words[1], "\n".join(body) + "\n"), "python": None})
            continue
        if info == "python":
            examples.append({"commands": [], "shown": [], "file": None, "python": "\n".join(body) + "\n"})
            continue
        if info == "sh":
            commands, pending = [], ""
            for raw in body:
                line = raw.rstrip()
                if line.endswith("\\"):
                    pending += line[:-1] + " "
                    continue
                line, pending = pending + line, ""
                stripped = line.strip()
                if stripped.startswith("#"):
                    if commands:
                        commands[-1][1].append(stripped[1:].strip())
                    continue
                if stripped.startswith("ido "):
                    commands.append([stripped.split(" #", 1)[0].strip(), []])
            examples.append({"commands": commands, "shown": [], "file": None, "python": None})
        elif info == "" and adjacent and examples and examples[-1]["commands"]:
            examples[-1]["shown"].extend(s for s in body if s.strip())
    return examples


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ido", required=True, help="the ido tool")
    ap.add_argument("--guide", required=True, help="docs/user-guide.md")
    ap.add_argument("--data", required=True, help="the shared scans' folder (../shared/data)")
    ap.add_argument("--python-path", help="folder of the ido Python module; without it Python examples are skipped")
    a = ap.parse_args()
    a.ido = os.path.abspath(a.ido)
    a.data = os.path.abspath(os.environ.get("IDO_SHARED_DATA") or a.data)
    if a.python_path:
        a.python_path = os.path.abspath(a.python_path)
    with open(a.guide, encoding="utf-8") as f:
        examples = parse_guide(f.read())
    have_data = os.path.isdir(a.data)
    failures, ran, skipped = [], 0, 0
    with tempfile.TemporaryDirectory(prefix="ido-guide-") as work:
        def run(command):
            argv = shlex.split(command.replace("../shared/data", a.data))
            argv[0] = a.ido
            return subprocess.run(argv, cwd=work, capture_output=True, text=True, timeout=600)

        later = []  # (command, shown lines) that need a file a later example writes
        for ex in examples:
            if ex["python"] is not None:
                code = ex["python"]
                if not a.python_path or ("../shared/data" in code and not have_data):
                    skipped += 1
                    continue
                failures.extend(check_python(code.replace("../shared/data", a.data), a.python_path, work))
                ran += 1
                continue
            if ex["file"]:
                with open(os.path.join(work, ex["file"][0]), "w", encoding="utf-8") as f:
                    f.write(ex["file"][1])
                continue
            printed = []
            for command, comment_lines in ex["commands"]:
                if "../shared/data" in command and not have_data:
                    skipped += 1
                    continue
                r = run(command)
                ran += 1
                if r.returncode != 0 and "no such file" in r.stderr:
                    later.append((command, comment_lines))
                    continue
                if r.returncode != 0:
                    failures.append(f"`{command}` exited {r.returncode}: {r.stderr.strip()[:300]}")
                    continue
                out = (r.stdout + r.stderr).splitlines()
                printed.extend(out)
                failures.extend(check(command, comment_lines, out))
            if ex["shown"] and printed:
                label = ex["commands"][-1][0] if len(ex["commands"]) == 1 else f"{ex['commands'][0][0]} ..."
                failures.extend(check(label, ex["shown"], printed))
        for command, comment_lines in later:
            r = run(command)
            if r.returncode != 0:
                failures.append(f"`{command}` exited {r.returncode}: {r.stderr.strip()[:300]}")
            else:
                failures.extend(check(command, comment_lines, (r.stdout + r.stderr).splitlines()))
    for f in failures:
        print("user guide:", f)
    print(f"user guide: {ran} commands run, {skipped} skipped (no shared data), {len(failures)} failures")
    return 1 if failures else 0


def check_python(code, python_path, work):
    """Failure messages of one Python example: its exit status and its commented figures."""
    env = dict(os.environ, PYTHONPATH=python_path, PYTHONDONTWRITEBYTECODE="1")
    r = subprocess.run([sys.executable, "-c", code], cwd=work, env=env, capture_output=True, text=True, timeout=600)
    if r.returncode != 0:
        return [f"the Python example exited {r.returncode}: {r.stderr.strip()[-300:]}"]
    shown = [line.split("#", 1)[1].strip() for line in code.splitlines()
             if line.lstrip().startswith("print(") and "#" in line]
    printed = r.stdout.splitlines()
    out = []
    for k, figure in enumerate(shown):
        if k >= len(printed):
            out.append(f"the Python example shows {figure}, but prints only {len(printed)} lines")
            continue
        digits = len(figure.split(".", 1)[1]) if "." in figure else 0
        try:
            if round(float(printed[k]), digits) != float(figure):
                out.append(f"the Python example shows {figure}, it prints {printed[k]}")
        except ValueError:
            out.append(f"the Python example shows {figure}, it prints \"{printed[k]}\"")
    return out


def check(command, shown, printed):
    """A failure message for each shown line that no printed line matches."""
    out = []
    by_shape = {}
    for p in printed:
        by_shape.setdefault(skeleton(p), []).append(p)
    for s in shown:
        candidates = by_shape.get(skeleton(s), [])
        if not candidates:
            out.append(f"`{command}`: the guide shows \"{s}\", which it does not print")
        elif not any(numbers(c) == numbers(s) for c in candidates):
            out.append(f"`{command}`: the guide shows \"{s}\", it prints \"{candidates[0]}\"")
    return out


if __name__ == "__main__":
    sys.exit(main())
