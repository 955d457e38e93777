#!/usr/bin/env python3
"""Every command the docs show works as written.

    docs_commands_test.py REPO BUILD [--doc FILE ...] [-v]
    docs_commands_test.py REPO BUILD --self-test

Reads README.md, docs/*.md and the components' README.md files (or the --doc files) and checks:

- Commands: every line of a shell code block (```sh, ```bash, ```shell, ```console, or a
  fence without a language), and every code span in a table row, whose program is one of
  alight's: `scripts/...`, `bench/...`, `fuzz/...`, `build/bin/...`, `alight-...`, `cmake`,
  `ctest`. Output belongs in ```text blocks, which are not read. For each such command the
  program must exist; every long option it uses must be one the program lists in its --help
  (or, for the few programs whose --help is not safe to run, one its source names); every path
  into the source tree it names must exist. A command that is cheap and offline is run and
  must exit 0: one with --dry-run, --list or --help, and alight-params. `scripts/demo` is run
  with --dry-run added (its own check of the mission, the files and the options), and nothing
  else that flies, builds, installs or needs hardware is run. `ctest -L` labels and `-R`
  patterns must select tests; `cmake --target`s must be built; `-D` options must be the
  project's.
- Links: every relative link's file exists, and its #anchor is a heading there.
- Parameter keys: every `vision.x.y`-style key in backticks whose first part is a section of a
  vehicle file is one `alight-params` prints (a `*` matches any part).
- Test names: every `Suite.Case` (or `Suite.*`) in backticks is a GoogleTest case in test/.
- The README's test command is `scripts/test`, exactly what CI's .ci/run runs.

Nothing here depends on timing: the subprocess timeout only stops a program that hangs.
--self-test checks that the checks fail where they should, on docs written to fail.
"""
import argparse
import fnmatch
import functools
import glob
import os
import re
import shlex
import subprocess
import sys
import tempfile

SHELL_INFOS = {"", "sh", "bash", "shell", "console"}
# Programs never run, not even with --help: they install, build and test everything, or write
# a key wherever their first argument says. Their options are checked against their source.
NEVER_RUN = {"scripts/test", "scripts/setup", "scripts/make-key",
             "build/bin/bench/bench_lcm_images", "build/bin/vision_bench"}
# Programs that talk to hardware or a network: their --help is read, but they are never run.
NEEDS_HARDWARE = {"build/bin/alight-camera", "build/bin/alight-calibrate", "build/bin/alight-mocap",
                  "build/bin/alight-mavlink", "build/bin/alight-link"}
# Long options whose presence makes a command cheap and offline to run.
RUN_OPTIONS = {"--dry-run", "--list", "--help"}
RUN_PROGRAMS = {"build/bin/alight-params"}
TIMEOUT_S = 300  # a hang guard only
PREFIXES = ("scripts/", "bench/", "fuzz/", "build/bin/")
# The sections of a vehicle file: a key in backticks that starts with one of them
# (`vision.landing.min_height_m`) must be one alight-params prints.
PARAM_ROOTS = {"vehicle", "cameras", "outer_loop", "autonomy", "vision"}
PROGRAM_WORD = re.compile(
    r"(^|[\s;&|(=])(scripts/|bench/|fuzz/|build/bin/|alight[-_]|cmake\b|ctest\b)")
TEST_MACRO = re.compile(r"^\s*TEST(?:_F|_P)?\(\s*(\w+)\s*,\s*(\w+)\s*\)", re.M)


class Checker:
    def __init__(self, repo, build, verbose=False, quiet=False):
        self.repo = os.path.abspath(repo)
        self.quiet = quiet
        self.build = os.path.abspath(build)
        self.verbose = verbose
        self.failures = []
        self.counts = {"run": 0, "dry-run": 0, "links": 0, "keys": 0, "tests": 0}
        self.env = dict(os.environ)
        self.env["ALIGHT_BUILD_DIR"] = self.build
        self.env["PATH"] = os.path.join(self.build, "bin") + os.pathsep + self.env.get("PATH", "")
        # Anything that would talk anyway stays on a port of its own.
        self.env["LCM_DEFAULT_URL"] = "udpm://239.255.76.67:7798?ttl=0"

    def fail(self, where, what):
        self.failures.append("%s: %s" % (where, what))
        if not self.quiet:
            print("FAIL %s: %s" % (where, what))

    def say(self, text):
        if self.verbose:
            print(text)

    # --- running ---------------------------------------------------------------------------

    def run(self, argv, cwd=None):
        try:
            p = subprocess.run(argv, cwd=cwd or self.repo, env=self.env, stdin=subprocess.DEVNULL,
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               timeout=TIMEOUT_S)
            return p.returncode, p.stdout.decode("utf-8", "replace")
        except subprocess.TimeoutExpired:
            return None, "no exit within %d s" % TIMEOUT_S
        except OSError as e:
            return None, str(e)

    # --- programs --------------------------------------------------------------------------

    def resolve(self, program):
        """(canonical name, path) of an alight program, or None for any other program."""
        if program.startswith("build/bin/"):
            return program, os.path.join(self.build, program[len("build/"):])
        if program.startswith(("alight-", "alight_")) and "/" not in program:
            return "build/bin/" + program, os.path.join(self.build, "bin", program)
        if program.startswith(PREFIXES):
            return program, os.path.join(self.repo, program)
        return None

    @functools.lru_cache(maxsize=None)
    def help_text(self, name, path):
        """What the program says it accepts, or None (after a failure) when it says nothing."""
        if name in NEVER_RUN:
            with open(path, "rb") as f:
                return f.read().decode("latin-1")
        rc, out = self.run([path, "--help"])
        base = os.path.basename(path)
        if rc == 0 or (rc is not None and out.strip() and
                       (re.search("usage", out, re.I) or base in out)):
            return out
        return None

    # --- one command -----------------------------------------------------------------------

    def check_command(self, where, tokens, text):
        while tokens and re.match(r"^[A-Za-z_][A-Za-z0-9_]*=", tokens[0]):
            self.check_paths(where, [tokens[0].split("=", 1)[1]])
            tokens = tokens[1:]
        while tokens and tokens[0] in ("sudo", "exec", "time"):
            tokens = tokens[1:]
        if not tokens:
            return
        program, args = tokens[0], tokens[1:]
        if program == "ctest":
            return self.check_ctest(where, args, text)
        if program == "cmake":
            return self.check_cmake(where, args, text)
        resolved = self.resolve(program)
        if resolved is None:
            return
        name, path = resolved
        if not (os.path.isfile(path) and os.access(path, os.X_OK)):
            return self.fail(where, "no such program: %s (%s)" % (program, path))
        args = [a.strip("[]") for a in args]
        failures_before = len(self.failures)
        self.check_paths(where, args)
        options = [a.split("=", 1)[0] for a in args if re.match(r"^--[A-Za-z]", a)]
        if options:
            known = self.help_text(name, path)
            if known is None:
                return self.fail(where, "%s --help says nothing it accepts" % program)
            for o in options:
                if not re.search(r"(?<![\w-])%s(?![\w-])" % re.escape(o), known):
                    self.fail(where, "%s has no option %s" % (program, o))
        elif name not in NEVER_RUN and self.help_text(name, path) is None:
            return self.fail(where, "%s --help fails" % program)
        if len(self.failures) > failures_before:
            return  # running it would only report the same fault again
        placeholder = any("$" in a or "<" in a or "*" in a or re.fullmatch(r"[A-Z][A-Z_]*", a)
                          for a in args)
        runnable = name not in NEVER_RUN and name not in NEEDS_HARDWARE and not placeholder
        argv = [path] + args
        if name == "scripts/demo" and "--dry-run" not in args:
            argv = argv + ["--dry-run"]
        elif not (runnable and args and (name in RUN_PROGRAMS or RUN_OPTIONS & set(args))):
            self.counts["dry-run"] += 1
            return self.say("ok (dry run) %s: %s" % (where, text))
        if not runnable:
            self.counts["dry-run"] += 1
            return self.say("ok (dry run) %s: %s" % (where, text))
        rc, out = self.run(argv)
        if rc != 0:
            return self.fail(where, "`%s` exited %s:\n%s" % (" ".join(argv), rc, out[-1500:]))
        self.counts["run"] += 1
        self.say("ok (ran) %s: %s" % (where, text))

    def check_paths(self, where, args):
        """Paths into the source tree (config/..., scripts/...) and the build's binaries exist."""
        tops = self.top_level()
        for a in args:
            for value in [a.split("=", 1)[1]] if re.match(r"^--?[\w-]+=", a) else [a]:
                if any(c in value for c in "$<>*~") or "/" not in value:
                    continue
                first = value.split("/", 1)[0]
                if value.startswith("build/bin/"):
                    target = os.path.join(self.build, value[len("build/"):])
                elif first in tops:
                    target = os.path.join(self.repo, value)
                else:
                    continue
                if not os.path.exists(target):
                    self.fail(where, "no such file: %s" % value)

    @functools.lru_cache(maxsize=None)
    def top_level(self):
        return frozenset(e for e in os.listdir(self.repo)
                         if os.path.isdir(os.path.join(self.repo, e)) and not e.startswith(".")
                         and e not in ("build", "logs") and not e.startswith("build-"))

    @functools.lru_cache(maxsize=None)
    def ctest_labels(self):
        rc, out = self.run(["ctest", "--print-labels"], cwd=self.build)
        return set(l.strip() for l in out.splitlines()[2:] if l.strip()) if rc == 0 else set()

    @functools.lru_cache(maxsize=None)
    def ctest_names(self):
        rc, out = self.run(["ctest", "-N"], cwd=self.build)
        return [m.group(1) for m in re.finditer(r"Test\s+#\d+: (\S+)", out)]

    def check_ctest(self, where, args, text):
        for i, a in enumerate(args[:-1]):
            if a == "-L":
                # The fuzz targets' tests live in the fuzz tree (build-fuzz), not in this build.
                if args[i + 1] != "fuzz" and args[i + 1] not in self.ctest_labels():
                    self.fail(where, "no CTest label %s" % args[i + 1])
            if a == "-R":
                if not any(re.search(args[i + 1], n) for n in self.ctest_names()):
                    self.fail(where, "ctest -R %s selects no test" % args[i + 1])
        self.counts["dry-run"] += 1
        self.say("ok (dry run) %s: %s" % (where, text))

    def check_cmake(self, where, args, text):
        cmake_text = ""
        for f in [os.path.join(self.repo, "CMakeLists.txt")] + glob.glob(
                os.path.join(self.repo, "cmake", "*.cmake")):
            with open(f) as fh:
                cmake_text += fh.read()
        for i, a in enumerate(args):
            if a.startswith("-D"):
                var = (a[2:] if len(a) > 2 else (args[i + 1] if i + 1 < len(args) else ""))
                var = var.split("=", 1)[0].split(":", 1)[0]
                if not var.startswith("CMAKE_") and var not in cmake_text:
                    self.fail(where, "CMake has no option %s" % var)
        if "--target" in args:
            for t in args[args.index("--target") + 1:]:
                if t.startswith("-"):
                    break
                if not any(os.path.exists(os.path.join(self.build, "bin", d, t))
                           for d in ("", "bench", "tests")):
                    self.fail(where, "no built target %s in %s/bin" % (t, self.build))
        self.counts["dry-run"] += 1
        self.say("ok (dry run) %s: %s" % (where, text))

    # --- a whole document ------------------------------------------------------------------

    def commands_of(self, path):
        """(line number, text) of every logical line in the shell blocks of a Markdown file, and
        of every code span in a table row that starts with a program: a results table's
        commands."""
        out, fence, info, pending, start = [], None, "", "", 0
        with open(path) as f:
            lines = f.read().splitlines()
        for n, line in enumerate(lines, 1):
            stripped = line.strip()
            if fence is None:
                m = re.match(r"^(`{3,}|~{3,})\s*([\w+-]*)", stripped)
                if m:
                    fence, info = m.group(1), m.group(2).lower()
                elif stripped.startswith("|"):
                    out += [(n, span) for span in re.findall(r"`([^`]+)`", stripped)
                            if span.startswith(PREFIXES + ("alight-",)) and
                            not re.match(r"^\S+\.(cpp|hpp|h|md|yaml|mjs|json)\b", span)]
                continue
            if stripped.startswith(fence):
                fence = None
                continue
            if info not in SHELL_INFOS:
                continue
            if not pending:
                start = n
            if stripped.endswith("\\"):
                pending += stripped[:-1] + " "
                continue
            text = (pending + stripped).strip()
            pending = ""
            if text.startswith("$ "):
                text = text[2:]
            if text and not text.startswith("#"):
                out.append((start, text))
        return out

    def check_document(self, path):
        rel = os.path.relpath(path, self.repo)
        for n, text in self.commands_of(path):
            where = "%s:%d" % (rel, n)
            if not PROGRAM_WORD.search(text):
                continue  # no alight program in it (ip, sed, openssl, ...)
            # A command substitution is a value, not a command to check.
            flat = re.sub(r"\$\([^()]*\)", "$SUBST", text)
            try:
                lexer = shlex.shlex(flat, posix=True, punctuation_chars=";&|<>()")
                lexer.whitespace_split = True
                tokens = list(lexer)
            except ValueError as e:
                self.fail(where, "cannot parse `%s`: %s" % (text, e))
                continue
            command = []
            skip_next = False
            for t in tokens + [";"]:
                if skip_next:
                    skip_next = False
                    continue
                if t and set(t) <= set(";&|()"):
                    self.check_command(where, command, text)
                    command = []
                elif t and set(t) <= set("<>&"):
                    if command and command[-1].isdigit():
                        command.pop()
                    skip_next = True
                else:
                    command.append(t)
        with open(path) as f:
            body = f.read()
        self.check_links(rel, path, body)
        self.check_keys(rel, body)
        self.check_test_names(rel, body)

    # --- links -----------------------------------------------------------------------------

    @staticmethod
    def anchors(path):
        slugs, seen, fence = set(), {}, None
        with open(path) as f:
            for line in f:
                s = line.strip()
                m = re.match(r"^(`{3,}|~{3,})", s)
                if m:
                    fence = None if fence and s.startswith(fence) else (fence or m.group(1))
                    continue
                if fence:
                    continue
                h = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
                if not h:
                    continue
                slug = re.sub(r"[^\w\- ]", "", h.group(1).lower()).replace(" ", "-")
                k = seen.get(slug, 0)
                seen[slug] = k + 1
                slugs.add(slug if k == 0 else "%s-%d" % (slug, k))
        return slugs

    def check_links(self, rel, path, body):
        body = re.sub(r"```.*?```", "", body, flags=re.S)
        for m in re.finditer(r"\]\(([^)\s]+)\)", body):
            target = m.group(1)
            if re.match(r"^[a-z]+:", target):
                continue
            line = body.count("\n", 0, m.start()) + 1
            file_part, _, anchor = target.partition("#")
            dest = os.path.normpath(os.path.join(os.path.dirname(path), file_part)) \
                if file_part else path
            self.counts["links"] += 1
            if not os.path.exists(dest):
                self.fail(rel, "link to a missing file: %s" % target)
            elif anchor and dest.endswith(".md") and anchor not in self.anchors(dest):
                self.fail(rel, "link to a missing heading: %s" % target)

    # --- parameter keys and test names -----------------------------------------------------

    @functools.lru_cache(maxsize=None)
    def param_keys(self):
        keys = set()
        params = os.path.join(self.build, "bin", "alight-params")
        dumps = [["--defaults", "vehicle"]] + [
            ["--dump", os.path.join(self.repo, "config", "vehicles", v)]
            for v in ("pelican.yaml", "starmac.yaml")]
        for argv in dumps:
            rc, out = self.run([params] + argv)
            path = []
            for line in out.splitlines():
                m = re.match(r"^( *)([A-Za-z_][\w]*):", line)
                if not m or line.lstrip().startswith("#"):
                    continue
                depth = len(m.group(1)) // 2
                path = path[:depth] + [m.group(2)]
                keys.add(".".join(path))
        return keys

    def check_keys(self, rel, body):
        keys = self.param_keys()
        for m in re.finditer(r"`([a-z_]+(?:\.[A-Za-z0-9_*]+)+)`", body):
            key = m.group(1)
            if (key.split(".", 1)[0] not in PARAM_ROOTS or
                    re.search(r"\.(ya?ml|md|[ch]pp|py)$", key)):
                continue
            self.counts["keys"] += 1
            if not any(fnmatch.fnmatchcase(k, key) for k in keys):
                self.fail(rel, "no parameter %s" % key)

    @functools.lru_cache(maxsize=None)
    def test_cases(self):
        cases = set()
        for f in glob.glob(os.path.join(self.repo, "test", "**", "*.cpp"), recursive=True):
            with open(f, errors="replace") as fh:
                cases.update("%s.%s" % m.groups() for m in TEST_MACRO.finditer(fh.read()))
        return cases

    def check_test_names(self, rel, body):
        cases = self.test_cases()
        suites = set(c.split(".", 1)[0] for c in cases)
        for m in re.finditer(r"`([A-Z][A-Za-z0-9]*)\.([A-Z][A-Za-z0-9]*|\*)`", body):
            suite, case = m.groups()
            self.counts["tests"] += 1
            if case == "*" and suite not in suites:
                self.fail(rel, "no test suite %s" % suite)
            elif case != "*" and "%s.%s" % (suite, case) not in cases:
                self.fail(rel, "no test %s.%s" % (suite, case))

    # --- the test command ------------------------------------------------------------------

    def check_test_command(self):
        readme = os.path.join(self.repo, "README.md")
        commands = [t.split("#", 1)[0].split() for _, t in self.commands_of(readme)]
        if ["scripts/test"] not in commands:
            self.fail("README.md", "no shell block runs `scripts/test`, CI's command")
        with open(os.path.join(self.repo, ".ci", "run")) as f:
            ci = [l.strip() for l in f if l.strip() and not l.lstrip().startswith("#")]
        if "exec scripts/test" not in ci:
            self.fail(".ci/run", "does not run `scripts/test`, the README's test command")


def documents(repo):
    docs = [os.path.join(repo, "README.md")] + sorted(glob.glob(os.path.join(repo, "docs", "*.md")))
    return docs + sorted(glob.glob(os.path.join(repo, "*", "README.md")))


def self_test(repo, build):
    """Docs written to fail: each line's fault must be found, the good lines must pass."""
    with tempfile.TemporaryDirectory() as tmp:
        os.makedirs(os.path.join(tmp, "docs"))
        bad = os.path.join(tmp, "docs", "bad.md")
        with open(bad, "w") as f:
            f.write("""# Bad

## A heading

```sh
scripts/no-such-script --list
build/bin/alight-no-such-binary --help
build/bin/alight-params --no-such-option
scripts/montecarlo --no-such-option 3
scripts/demo underwater
build/bin/alight-params --dump config/vehicles/no_such_vehicle.yaml
ctest -L no_such_label
cmake --build build --target no_such_target
cmake -S . -B build -DALIGHT_NO_SUCH_OPTION=ON
```

| figure | command |
|---|---|
| a table's command | `build/bin/alight_families_bench --runs 3 --no-such-table-option` |

[gone](no-such-page.md), [no heading](bad.md#no-such-heading), `vision.landing.no_such_key`,
`NoSuchSuite.*`, `HomographyTest.NoSuchCase`.
""")
        good = os.path.join(tmp, "docs", "good.md")
        with open(good, "w") as f:
            f.write("""# Good

## A heading

```sh
scripts/faults --list                       # runs
build/bin/alight-params --defaults camera
scripts/demo ingress --seed 3               # dry-run by the demo itself
ALIGHT_X=config/vehicles/pelican.yaml build/bin/alight-vision \\
    --config config/vehicles/pelican.yaml --mission landing
ip route get 239.255.76.67                  # not an alight program: not checked
ctest -L vision
```

```text
scripts/no-such-script                      # output, not a command
```

[here](good.md#a-heading), `vision.landing.min_height_m`, `vision.star.*`,
`HomographyTest.*`, `HomographyTest.SameSeedGivesIdenticalResults`.
""")
        expected = ["no such program: scripts/no-such-script",
                    "no such program: build/bin/alight-no-such-binary",
                    "alight-params has no option --no-such-option",
                    "scripts/montecarlo has no option --no-such-option",
                    "scripts/demo underwater --dry-run` exited",
                    "no such file: config/vehicles/no_such_vehicle.yaml",
                    "no CTest label no_such_label",
                    "alight_families_bench has no option --no-such-table-option",
                    "no built target no_such_target", "CMake has no option ALIGHT_NO_SUCH_OPTION",
                    "link to a missing file: no-such-page.md",
                    "link to a missing heading: bad.md#no-such-heading",
                    "no parameter vision.landing.no_such_key", "no test suite NoSuchSuite",
                    "no test HomographyTest.NoSuchCase"]
        ok = True
        c = Checker(repo, build, quiet=True)
        c.check_document(good)
        if c.failures:
            print("self-test: the good document failed:\n  " + "\n  ".join(c.failures))
            ok = False
        if c.counts["run"] < 3:
            print("self-test: only %d commands of the good document ran" % c.counts["run"])
            ok = False
        c = Checker(repo, build, quiet=True)
        c.check_document(bad)
        for e in expected:
            if not any(e in f for f in c.failures):
                print("self-test: not found: %s" % e)
                ok = False
            else:
                print("self-test: found as it should be: %s" % e)
        if len(c.failures) > len(expected):
            print("self-test: more failures than faults:\n  " + "\n  ".join(c.failures))
            ok = False
    print("self-test: %s" % ("passed" if ok else "FAILED"))
    return 0 if ok else 1


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("repo")
    ap.add_argument("build")
    ap.add_argument("--doc", action="append", help="check this file only (repeatable)")
    ap.add_argument("--self-test", action="store_true")
    ap.add_argument("-v", "--verbose", action="store_true")
    args = ap.parse_args()
    if args.self_test:
        return self_test(args.repo, args.build)
    c = Checker(args.repo, args.build, args.verbose)
    for path in args.doc or documents(c.repo):
        c.check_document(os.path.abspath(path))
    if not args.doc:
        c.check_test_command()
    print("docs: %d commands run, %d dry-run, %d links, %d parameter keys, %d test names; "
          "%d failures" % (c.counts["run"], c.counts["dry-run"], c.counts["links"],
                           c.counts["keys"], c.counts["tests"], len(c.failures)))
    return 1 if c.failures else 0


if __name__ == "__main__":
    sys.exit(main())
