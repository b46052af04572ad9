#!/usr/bin/env python3
"""scripts/check_structure.py on small trees made for the purpose: it must
find an include cycle between folders and a function over 150 lines, and
pass a tree with neither."""
import os
import subprocess
import sys
import tempfile
import unittest

SCRIPT = os.path.join(os.path.dirname(__file__), "..", "..", "..", "scripts",
                      "check_structure.py")


def write(root, path, text):
    full = os.path.join(root, path)
    os.makedirs(os.path.dirname(full), exist_ok=True)
    with open(full, "w", encoding="utf-8") as out:
        out.write(text)


def check(root):
    run = subprocess.run([sys.executable, SCRIPT, "--root", root],
                         capture_output=True, text=True)
    return run.returncode, run.stdout


class CheckStructureTest(unittest.TestCase):
    def test_a_clean_tree_passes(self):
        with tempfile.TemporaryDirectory() as root:
            write(root, "solver/mesh/mesh.h", "#pragma once\nint Nodes();\n")
            write(root, "solver/fem/tet4.cc", '#include "mesh/mesh.h"\nint F() { return Nodes(); }\n')
            code, out = check(root)
            self.assertEqual(code, 0, out)

    def test_an_include_cycle_between_folders_fails_naming_both(self):
        with tempfile.TemporaryDirectory() as root:
            write(root, "solver/fem/tet4.h", '#pragma once\n#include "material/law.h"\n')
            write(root, "solver/material/law.h", '#pragma once\n#include "fem/tet4.h"\n')
            code, out = check(root)
            self.assertEqual(code, 1, out)
            self.assertIn("include cycle between folders: solver/fem <-> solver/material", out)
            self.assertIn("solver/material/law.h includes solver/fem/tet4.h", out)

    def test_a_cycle_through_a_third_folder_is_found(self):
        with tempfile.TemporaryDirectory() as root:
            write(root, "solver/a/a.h", '#include "b/b.h"\n')
            write(root, "solver/b/b.h", '#include "c/c.h"\n')
            write(root, "solver/c/c.h", '#include "a/a.h"\n')
            code, out = check(root)
            self.assertEqual(code, 1, out)
            self.assertIn("solver/a <-> solver/b <-> solver/c", out)

    def test_a_long_function_fails_and_150_lines_pass(self):
        with tempfile.TemporaryDirectory() as root:
            body = "  int x = 0;\n" * 148  # 148 + the two brace lines = 150
            write(root, "server/app/ok.cc", "int Fits() {\n" + body + "}\n")
            code, out = check(root)
            self.assertEqual(code, 0, out)
            write(root, "server/app/long.cc", "int TooLong() {\n" + body + "  x++;\n}\n")
            code, out = check(root)
            self.assertEqual(code, 1, out)
            self.assertIn("function over 150 lines: TooLong (151 lines) at server/app/long.cc:1", out)


    def test_a_lower_target_including_a_higher_one_fails(self):
        with tempfile.TemporaryDirectory() as root:
            write(root, "solver/scene/problem.h", "#pragma once\n")
            write(root, "solver/mesh/mesh.cc", '#include "scene/problem.h"\n')
            code, out = check(root)
            self.assertEqual(code, 1, out)
            self.assertIn("include across targets: solver/mesh/mesh.cc (pba_fem) includes "
                          "solver/scene/problem.h (pba_solver)", out)

    def test_the_server_and_client_see_only_public_solver_headers(self):
        with tempfile.TemporaryDirectory() as root:
            write(root, "solver/include/pba/status.h", "#pragma once\n")
            write(root, "solver/atlas/atlas_build.h", '#include "pba/status.h"\n')
            write(root, "solver/analysis/newton_static.h", "#pragma once\n")
            write(root, "server/service/a.cc",
                  '#include "atlas/atlas_build.h"\n#include "pba/status.h"\n')
            code, out = check(root)
            self.assertEqual(code, 0, out)
            write(root, "server/service/b.cc", '#include "analysis/newton_static.h"\n')
            write(root, "client_cli/c.cc", '#include "atlas/atlas_build.h"\n')
            code, out = check(root)
            self.assertEqual(code, 1, out)
            self.assertIn("server/service/b.cc (server) includes solver/analysis/newton_static.h",
                          out)
            self.assertIn("client_cli/c.cc (client) includes solver/atlas/atlas_build.h", out)


if __name__ == "__main__":
    unittest.main()
