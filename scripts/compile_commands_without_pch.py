#!/usr/bin/env python3
"""The build's compile database without its precompiled headers, for scripts/lint's clang-tidy.

usage: compile_commands_without_pch.py BUILD_DIR OUT_DIR

The build precompiles the standard and third-party headers (cmake/precompiled_headers.cmake) and
GCC's compile commands name them with `-include <target>.dir/cmake_pch.hxx`. clang-tidy cannot
read GCC's precompiled form, and a file that forgot an include compiles here only because the
precompiled header supplies it. Without these two flags clang-tidy reads each file as a build
without precompiled headers would, so a missing include is an error in the lint.
Writes OUT_DIR/compile_commands.json.
"""
import json
import os
import shlex
import sys


def without_pch(arguments):
    kept = []
    for a in arguments:
        if a.endswith("cmake_pch.hxx") and kept and kept[-1] == "-include":
            kept.pop()  # the flag and the precompiled header it names
        elif a != "-Winvalid-pch":
            kept.append(a)
    return kept


def main():
    build, out = sys.argv[1], sys.argv[2]
    with open(os.path.join(build, "compile_commands.json")) as f:
        entries = json.load(f)
    for e in entries:
        if "arguments" in e:
            e["arguments"] = without_pch(e["arguments"])
        else:
            e["command"] = shlex.join(without_pch(shlex.split(e["command"])))
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "compile_commands.json"), "w") as f:
        json.dump(entries, f, indent=1)


if __name__ == "__main__":
    main()
