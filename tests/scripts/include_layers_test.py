#!/usr/bin/env python3
"""Include direction of the top-level source folders (issue 12, "folders that are layers").

Every project include is written folder-relative to the repository root ("solvers/dem_world.hpp").
The folders form layers, lowest first (LAYERS below): a file may include files of its own folder and
of lower layers, never of a higher one. GRANDFATHERED lists tolerated upward includes, each with
where its code should move; issue 12 emptied it and it may only shrink. The test fails on an upward
include not in the list, on a list entry that no longer occurs (delete it), and on an include whose
folder is not in the layer table. docs/architecture.md explains the layers."""
import pathlib
import re
import unittest

ROOT = pathlib.Path(__file__).resolve().parents[2]

# the layers, lowest first; folders in one inner list share a layer
LAYERS = [
    # OpenCL C kernels (*.cl) and the plain-C layouts shared with C++ (common.h, dem_types.h)
    ["kernels"],
    # OpenCL runtime (device, typed buffers, programs from the embedded kernels, scan), error types, and the
    # utilities every layer uses (progress lines, data files, atomic writes)
    ["host"],
    # the machine: rigid bodies, joints, cylinders, driveline, tyres, wheel loader, sensors, effects, scenarios
    ["vehicle"],
    # the particle world and its coupling: particles, DEM stepper, contact sweeps, bucket rows, split solver,
    # rigid tools, digging
    ["solvers"],
    # the soil on the DEM world: piles, settling, heap/shear/collapse/cutting tests, bucket fill
    ["terrain"],
    # whole scenario runs on a pile with the machine: the digging run and the force-feedback sweep
    ["digging"],
    # measured runs, metrics, replay, residuals, diagnosis: simulation against the field
    ["sim2real"],
    # presentation: particle files, images, plots, ray-traced renders
    ["io"],
    # the two front ends, which may not include each other: the `talus` command-line tool, one file per
    # subcommand, and the embedding facade (talus/talus.hpp) for programs that run talus inside themselves
    ["apps", "embed"],
    # the Python package: the facade bound with pybind11 (python/bindings.cpp includes embed/talus.hpp)
    ["python"],
]

# folders of one layer that may include each other, as (including, included); none today
PEERS = set()

# the files whose includes are checked
SOURCE_SUFFIXES = (".cpp", ".hpp", ".h", ".cl")

# the upward includes that exist today, as (file, included file, why); issue 12 removed the last ten,
# so the list stays empty: an include that must run upward is a design change for docs/architecture.md
GRANDFATHERED = []

# comments (blanked, newlines kept), raw strings (blanked) and ordinary literals (kept as they are),
# matched left to right so that "/*" inside a string or "//" inside a comment is read correctly;
# an ordinary literal ends at its line, so a stray quote (a digit separator) cannot swallow code
_LEXEMES = re.compile(
    r"""//[^\n]*"""
    r"""|/\*.*?(?:\*/|\Z)"""
    r"""|(?<![A-Za-z0-9_])(?:u8|[uUL])?R"(?P<delim>[^()\\\s"]{0,16})\(.*?(?:\)(?P=delim)"|\Z)"""
    r"""|"(?:\\.|[^"\\\n])*\""""
    r"""|'(?:\\.|[^'\\\n])*'""",
    re.DOTALL)
_INCLUDE = re.compile(r'[ \t]*#[ \t]*include[ \t]*"([^"\n]*)"')


def _blank(match):
    text = match.group(0)
    if text[0] in "\"'":
        return text
    return re.sub(r"[^\n]", " ", text)


def parse_includes(text):
    """The quoted includes of one source text, as (line, path), outside comments and raw strings."""
    code = _LEXEMES.sub(_blank, text)
    found = []
    for number, line in enumerate(code.split("\n"), 1):
        match = _INCLUDE.match(line)
        if match:
            found.append((number, match.group(1)))
    return found


def read_sources(root, layers=LAYERS):
    """Every source file under the layer folders, as {folder-relative path: text}."""
    sources = {}
    for folder in (f for layer in layers for f in layer):
        for path in sorted((root / folder).rglob("*")):
            if path.is_file() and path.suffix in SOURCE_SUFFIXES:
                sources[path.relative_to(root).as_posix()] = path.read_text(encoding="utf-8", errors="replace")
    return sources


def check(sources, layers=LAYERS, peers=PEERS, grandfathered=GRANDFATHERED):
    """The rule's violations in `sources` ({path: text}), one message each; empty when all is well."""
    problems = []
    rank = {}
    for index, layer in enumerate(layers):
        for folder in layer:
            if folder in rank:
                problems.append(f"LAYERS: folder '{folder}' appears in two layers")
            rank.setdefault(folder, index)
    order = " < ".join(" = ".join(layer) for layer in layers)
    rule = f"rule: a file includes only its own folder and lower layers ({order})"
    for a, b in sorted(peers):
        if rank.get(a) is None or rank.get(a) != rank.get(b):
            problems.append(f"PEERS: ({a}, {b}) are not two folders of one layer")

    allowed = set()
    for file, included, _ in grandfathered:
        if (file, included) in allowed:
            problems.append(f"GRANDFATHERED: {file} -> {included} is listed twice: delete one entry")
        allowed.add((file, included))
    seen = set()

    for path in sorted(sources):
        here = path.split("/")[0]
        for line, included in parse_includes(sources[path]):
            there = included.split("/")[0] if "/" in included else ""
            where = f'{path}:{line}: #include "{included}"'
            if there not in rank:
                named = f"folder '{there}'" if there else "no folder"
                problems.append(f"{where} names {named}, not a layer of LAYERS; {rule}; "
                                f"include by the folder-relative path, or add the folder to LAYERS")
            elif here == there or rank[there] < rank[here] or (here, there) in peers:
                if (path, included) in allowed:
                    seen.add((path, included))
                    problems.append(f"{where}: GRANDFATHERED lists it, but it no longer goes upward: "
                                    f"delete the entry from tests/scripts/include_layers_test.py")
            elif (path, included) in allowed:
                seen.add((path, included))
            elif rank[there] == rank[here]:
                problems.append(f"{where}: '{here}' and '{there}' share a layer but are not PEERS; {rule}")
            else:
                problems.append(f"{where}: '{here}' (layer {rank[here]}) includes the higher layer "
                                f"'{there}' (layer {rank[there]}); {rule}; move what it needs down, or this file up "
                                f"(docs/architecture.md, \"Where new code goes\"), rather than adding to GRANDFATHERED")

    for file, included in sorted(allowed - seen):
        problems.append(f"GRANDFATHERED: {file} -> {included} no longer occurs: "
                        f"delete the entry from tests/scripts/include_layers_test.py")
    return problems


class IncludeLayersTest(unittest.TestCase):
    def assert_layered(self, problems):
        if problems:
            self.fail(f"{len(problems)} problem(s) with the include layers:\n" + "\n".join(problems))

    def test_repository_includes_go_downward(self):
        sources = read_sources(ROOT)
        # guard against a wrong root: the scan must see the project's folders
        self.assertIn("solvers/dem_world.hpp", sources, f"no sources under {ROOT}")
        self.assert_layered(check(sources))


class CheckerTest(unittest.TestCase):
    """The parser and the rule on small in-memory trees."""

    # a small order for the synthetic trees: low < mid < top, with peer folders side and wing in mid
    LAYERS = [["low"], ["mid", "side", "wing"], ["top"]]
    PEERS = {("mid", "side")}

    def problems(self, sources, grandfathered=()):
        return check(sources, self.LAYERS, self.PEERS, list(grandfathered))

    def test_parser_reads_includes_outside_comments_and_strings(self):
        text = "\n".join([
            '#include "low/a.hpp"',
            '  #  include   "low/b.h"  // why',
            "#include <vector>",
            '// #include "top/commented.hpp"',
            '/* block comment with data/*.json inside',
            '#include "top/in_block.hpp"',
            '*/ #include "low/after_block.hpp"',
            'const char* s = "/* not a comment";',
            '#include "low/after_string.cl"',
            'auto raw = R"x(',
            '#include "top/in_raw_string.hpp"',
            ')x";',
            "int n = 1'000;",
            '#include "low/after_separator.hpp"',
        ])
        self.assertEqual(parse_includes(text), [
            (1, "low/a.hpp"), (2, "low/b.h"), (7, "low/after_block.hpp"), (9, "low/after_string.cl"),
            (14, "low/after_separator.hpp")])

    def test_downward_same_folder_and_peer_includes_pass(self):
        self.assertEqual([], self.problems({
            "top/t.cpp": '#include "top/t.hpp"\n#include "mid/m.hpp"\n#include "low/l.h"\n',
            "mid/m.hpp": '#include "low/l.h"\n#include "side/s.hpp"\n'}))

    def test_synthetic_upward_include_fails_naming_file_line_and_rule(self):
        problems = self.problems({"low/l.cpp": '#include "low/l.hpp"\n\n#include "top/t.hpp"\n'})
        self.assertEqual(1, len(problems), problems)
        self.assertIn('low/l.cpp:3: #include "top/t.hpp"', problems[0])
        self.assertIn("includes the higher layer 'top'", problems[0])
        self.assertIn("rule: a file includes only its own folder and lower layers (low < mid = side = wing < top)",
                      problems[0])

    def test_same_layer_needs_peers(self):
        problems = self.problems({"side/s.cpp": '#include "mid/m.hpp"\n', "mid/w.cpp": '#include "wing/w.hpp"\n'})
        self.assertEqual(2, len(problems), problems)
        self.assertIn("'mid' and 'wing' share a layer but are not PEERS", problems[0])
        self.assertIn("'side' and 'mid' share a layer but are not PEERS", problems[1])

    def test_grandfathered_passes_and_stale_entries_fail(self):
        sources = {"low/l.cpp": '#include "top/t.hpp"\n', "mid/m.cpp": '#include "low/l.hpp"\n'}
        self.assertEqual([], self.problems(sources, [("low/l.cpp", "top/t.hpp", "why")]))
        gone = self.problems(sources, [("low/l.cpp", "top/t.hpp", "why"), ("low/l.cpp", "top/gone.hpp", "why")])
        self.assertEqual(1, len(gone), gone)
        self.assertIn("low/l.cpp -> top/gone.hpp no longer occurs", gone[0])
        self.assertIn("delete the entry", gone[0])
        downward = self.problems(sources, [("low/l.cpp", "top/t.hpp", "why"), ("mid/m.cpp", "low/l.hpp", "why")])
        self.assertEqual(1, len(downward), downward)
        self.assertIn("mid/m.cpp:1", downward[0])
        self.assertIn("no longer goes upward: delete the entry", downward[0])

    def test_unknown_folders_fail(self):
        problems = self.problems({"mid/m.cpp": '#include "tests/util.hpp"\n#include "m.hpp"\n'})
        self.assertEqual(2, len(problems), problems)
        self.assertIn("mid/m.cpp:1: #include \"tests/util.hpp\" names folder 'tests', not a layer", problems[0])
        self.assertIn("mid/m.cpp:2: #include \"m.hpp\" names no folder", problems[1])

    def test_bad_tables_fail(self):
        problems = check({}, [["a"], ["b", "a"]], {("a", "b")}, [])
        self.assertEqual(2, len(problems), problems)
        self.assertIn("folder 'a' appears in two layers", problems[0])
        self.assertIn("PEERS: (a, b) are not two folders of one layer", problems[1])


if __name__ == "__main__":
    unittest.main()
