# SPDX-License-Identifier: Apache-2.0
"""A sample in the docs is a test: every fenced python, lua and csharp block of docs/*.md,
README.md and the bindings' READMEs is taken from its page and run as written, and so is the
Unity package's PressCube sample. (The docs' C programs are built and run by tests/packaging.)

A C# program (a block with `static void Main`) is built and run by the commands of the page's sh
block that names its file, word for word, from a folder laid out as the source tree (bindings/,
and build/ holding libmica); a C# fragment runs as the body of a Main, with a stand-in for the
UnityEngine types it uses (UnityEngine.cs).

Each must run without error. A sample that prints the force on its sphere, one line a step
("step 12: 1.794 N", the vertical component, N), is checked against the physics of the scene the
samples share: a sphere of radius R = 2 cm made 5 mm above a 10 cm cube (E = 10 kPa, Poisson ratio
0.3, the body def's default) fixed at its base, pressed 1 mm a step.
  - It starts out of contact: the first step has no force (a sphere made inside the cube and
    posed above it would drag the tissue up and be pulled down, 10 N and more).
  - The cube only ever pushes: no step has a downward force.
  - At the last step (k = 29: 24 mm deep) the force is Hertz's, 4/3 E/(1 - nu^2) sqrt(R) d^1.5 =
    7.7 N, within a factor 2 (a coarse mesh, a finite cube, gravity in some samples).
Exit 77 (a skip) when no runtime is there for any sample.

Environment (tests/bindings/CMakeLists.txt): MICA_SOURCE_DIR, MICA_LIBRARY, MICA_LIBRARY_DIR,
MICA_TEST_WORK_DIR.
"""
import glob
import os
import re
import shutil
import subprocess
import sys

SOURCE = os.environ["MICA_SOURCE_DIR"]
WORK = os.path.join(os.environ["MICA_TEST_WORK_DIR"], "doc_samples")
HERE = os.path.dirname(os.path.abspath(__file__))
PAGES = sorted(glob.glob(os.path.join(SOURCE, "docs", "*.md"))) + [os.path.join(SOURCE, "README.md")] + sorted(
    glob.glob(os.path.join(SOURCE, "bindings", "**", "README.md"), recursive=True))
PRESS_CUBE = os.path.join(SOURCE, "bindings", "csharp", "com.libmica.mica", "Samples~", "PressCube", "PressCube.cs")

E, NU, R = 1e4, 0.3, 0.02           # Pa, -, m
START_GAP, STEP = 0.005, 0.001      # m


def hertz(depth):
    return 4.0 / 3.0 * E / (1 - NU * NU) * R ** 0.5 * depth ** 1.5


def fenced_blocks(page):
    """(language, first line number, code) of each fenced block of a Markdown page."""
    blocks, language, start, lines = [], None, 0, []
    for number, line in enumerate(open(page, encoding="utf-8"), 1):
        fence = re.match(r"^```(\w*)\s*$", line)
        if fence and language is None:
            language, start, lines = fence.group(1), number + 1, []
        elif fence:
            blocks.append((language, start, "".join(lines)))
            language = None
        elif language is not None:
            lines.append(line)
    return blocks


def forces_of(output):
    """The forces a sample printed, one a step ("step k: F N")."""
    return [float(f) for f in re.findall(r"^step \d+: (-?\d+\.\d+) N$", output, re.M)]


def physics_error(forces):
    """What is wrong with a sample's forces (see the top of this file), or None."""
    if forces[0] != 0:
        return "the first step has a force of %g N: the sphere starts above the cube" % forces[0]
    if min(forces) < 0:
        return "the cube pulls the sphere down (%g N at step %d)" % (min(forces), forces.index(min(forces)))
    depth = STEP * (len(forces) - 1) - START_GAP
    if not 0.5 * hertz(depth) <= forces[-1] <= 2 * hertz(depth):
        return "%g N at %g mm deep, Hertz says %.3g N" % (forces[-1], depth * 1e3, hertz(depth))
    return None


def run_command(command, **kwargs):
    """What `command` printed; raises RuntimeError with its output when it fails."""
    result = subprocess.run(command, capture_output=True, text=True, timeout=120, **kwargs)
    if result.returncode != 0:
        raise RuntimeError("exit code %d:\n%s%s" % (result.returncode, result.stdout, result.stderr))
    return result.stdout


USING = re.compile(r"^using [\w.]+;\s*$")  # a using directive (not a using statement)


class Runners:
    """Runs the samples of each language (a runtime missing: available() is false)."""

    def __init__(self):
        self.python = "/usr/bin/python3" if os.path.exists("/usr/bin/python3") else shutil.which("python3")
        if self.python and subprocess.run([self.python, "-c", "import numpy"], capture_output=True).returncode:
            self.python = None
        cdef = os.path.join(os.environ["MICA_BINDINGS_BUILD_DIR"], "luajit", "mica_cdef.lua")
        self.luajit = os.path.exists(cdef) and shutil.which("luajit")
        self.mono = shutil.which("mcs") and shutil.which("mono")
        self.dll = None  # LibMica.dll, as the docs' C# program's commands built it

    def available(self, language):
        return {"python": self.python, "lua": self.luajit, "csharp": self.mono}[language]

    def run(self, language, code, page):
        """Runs a sample (code None: the PressCube sample) and returns what it printed."""
        if language == "python":
            env = dict(os.environ, PYTHONPATH=os.path.join(SOURCE, "bindings", "python"), PYTHONDONTWRITEBYTECODE="1")
            return run_command([self.python, "-c", code], env=env, cwd=WORK)
        if language == "lua":
            # The module from the source tree, its generated cdef from the build tree (as run_luajit.sh).
            lua_path = "%s/bindings/luajit/?.lua;%s/luajit/?.lua;;" % (SOURCE, os.environ["MICA_BINDINGS_BUILD_DIR"])
            return run_command([self.luajit, "-"], input=code, env=dict(os.environ, LUA_PATH=lua_path), cwd=WORK)
        if code is None:
            return self.csharp_with_unity({"PressCube.cs": open(PRESS_CUBE).read(),
                                           "PressCubeDriver.cs": open(os.path.join(HERE, "PressCubeDriver.cs")).read()})
        if "static void Main" in code:
            return self.csharp_program(code, page)
        # A fragment: the body of a Main, its using directives above it.
        lines = code.splitlines(True)
        program = "%sstatic class Sample\n{\n    static void Main()\n    {\n%s    }\n}\n" % (
            "".join(l for l in lines if USING.match(l)), "".join(l for l in lines if not USING.match(l)))
        return self.csharp_with_unity({"Sample.cs": program})

    def csharp_program(self, code, page):
        # Its file is named on its first line ("// press.cs: ..."); the page's sh block naming that
        # file builds and runs it, word for word, from a folder laid out as the source tree.
        filename = re.match(r"^// (\S+\.cs):", code).group(1)
        commands = [c for lang, _, c in fenced_blocks(page) if lang == "sh" and filename in c.split()]
        if not commands:
            raise RuntimeError("no sh block of %s builds %s" % (os.path.basename(page), filename))
        folder = os.path.join(WORK, os.path.splitext(filename)[0])
        shutil.rmtree(folder, ignore_errors=True)
        os.makedirs(folder)
        os.symlink(os.path.join(SOURCE, "bindings"), os.path.join(folder, "bindings"))
        os.symlink(os.environ["MICA_LIBRARY_DIR"], os.path.join(folder, "build"))
        with open(os.path.join(folder, filename), "w") as f:
            f.write(code)
        output = run_command(["bash", "-euc", commands[0]], cwd=folder)
        self.dll = os.path.join(folder, "LibMica.dll")
        return output

    def csharp_with_unity(self, sources):
        # Built against the LibMica.dll of the docs' commands, with UnityEngine.cs standing in for Unity.
        if self.dll is None or not os.path.exists(self.dll):
            raise RuntimeError("no LibMica.dll: the docs' C# program (docs/bindings.md) builds it")
        folder = os.path.join(WORK, "unity")
        os.makedirs(folder, exist_ok=True)
        paths = [os.path.join(HERE, "UnityEngine.cs")]
        for filename, text in sources.items():
            paths.append(os.path.join(folder, filename))
            with open(paths[-1], "w") as f:
                f.write(text)
        exe = os.path.join(folder, "sample.exe")
        run_command(["mcs", "-nologo", "-unsafe", "-r:System.Numerics", "-r:System.Numerics.Vectors", "-r:" + self.dll,
                     "-out:" + exe] + paths)
        env = dict(os.environ, LD_LIBRARY_PATH=os.environ["MICA_LIBRARY_DIR"], MONO_PATH=os.path.dirname(self.dll))
        return run_command(["mono", exe], env=env)


def main():
    os.makedirs(WORK, exist_ok=True)
    runners = Runners()
    samples = []  # (language, name, code, page)
    for page in PAGES:
        for language, line, code in fenced_blocks(page):
            if language in ("python", "lua", "csharp"):
                samples.append((language, "%s:%d" % (os.path.relpath(page, SOURCE), line), code, page))
    # C# programs first: their documented commands build the LibMica.dll the other C# samples use.
    samples.sort(key=lambda sample: not (sample[0] == "csharp" and "static void Main" in sample[2]))
    samples.append(("csharp", os.path.relpath(PRESS_CUBE, SOURCE), None, None))

    failed, ran, printed = [], 0, set()
    for language, name, code, page in samples:
        if not runners.available(language):
            print("SKIP %s (no %s runtime)" % (name, language))
            continue
        ran += 1
        try:
            forces = forces_of(runners.run(language, code, page))
            error = physics_error(forces) if forces else None
        except (RuntimeError, subprocess.TimeoutExpired) as e:
            forces, error = [], str(e)
        if forces:
            printed.add(language)
        if error:
            failed.append(name)
            print("FAIL %s: %s" % (name, error))
            continue
        if forces:
            depth = STEP * (len(forces) - 1) - START_GAP
            print("ok   %s: no force at first, never a pull, %.3f N at %g mm deep (Hertz: %.3f N)"
                  % (name, forces[-1], depth * 1e3, hertz(depth)))
        else:
            print("ok   %s (runs; prints no force)" % name)

    # Each language with a runtime has at least one sample whose forces are checked.
    for language in ("python", "lua", "csharp"):
        if runners.available(language) and language not in printed:
            failed.append(language)
            print("FAIL no %s sample prints its force ('step k: F N'), so none was checked" % language)
    if ran == 0:
        print("SKIP: no python3 with numpy, no luajit, no mcs and mono")
        return 77
    print("%d samples run, %d failed" % (ran, len(failed)))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
