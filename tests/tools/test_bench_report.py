"""tools/bench-report on the committed sample (bench_sample.txt): the min / median / max
rows per target, set, mode, H and N with the worst case's policy and scan and the issue's
targets beside the evolved rows; the evolved and random sets in separate tables; bad input
named by file and line with exit status 2; heading mismatches listed with exit status 1."""
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
TOOLS = os.environ.get("QNAV_TOOLS_DIR") or os.path.join(HERE, "..", "..", "tools")
REPORT = os.path.join(TOOLS, "bench-report")
SAMPLE = os.path.join(HERE, "bench_sample.txt")
GOOD = "M\ttarget=avr\tmode=network\tH=12\tN=32\tpolicy=e12-a\tset=evolved\tscan=clear:0\t120000\n"


def run(*args, stdin=None):
    return subprocess.run([sys.executable, REPORT, *args], input=stdin, capture_output=True,
                          text=True, timeout=300)


def with_file(text, *args):
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "bench.txt")
        with open(path, "w") as f:
            f.write(text)
        return path, run(path, *args)


class Tables(unittest.TestCase):
    def setUp(self):
        self.res = run(SAMPLE)
        self.lines = self.res.stdout.splitlines()

    def section(self, title):
        start = self.lines.index(title)
        end = next((i for i in range(start + 1, len(self.lines)) if self.lines[i].startswith("####")),
                   len(self.lines))
        return self.lines[start:end]

    def test_row_has_min_lower_median_max_worst_case_and_target(self):
        self.assertEqual(self.res.returncode, 0, self.res.stderr)
        evolved = self.section("#### ATmega128 (simavr, cycles at 16 MHz): evolved set")
        self.assertIn("| network | 12 | 32 | 4 | 120 000 | 205 000 | 980 000 | e12-a, dense:3 | "
                      "worst <= 100 000; median <= 60 000 |", evolved)

    def test_random_set_has_its_own_table_without_targets(self):
        random = self.section("#### ATmega128 (simavr, cycles at 16 MHz): random set")
        self.assertIn("| network | 12 | 32 | 1 | 630 000 | 630 000 | 630 000 | r12-vec, random:0 |  |",
                      random)
        evolved = self.section("#### ATmega128 (simavr, cycles at 16 MHz): evolved set")
        self.assertFalse(any("r12-vec" in line for line in evolved))

    def test_table_mode_target_applies_to_any_hidden_count(self):
        self.assertIn("| table | 12 | 32 | 2 | 34 000 | 34 000 | 36 500 | e12-a, behind:2 | "
                      "median <= 6 000; worst <= 8 000 |", self.lines)

    def test_host_values_are_shown_in_ns(self):
        host = self.section("#### Host (ns per step, median of repetitions): evolved set")
        self.assertIn("| network | 12 | 32 | 1 | 1681.5 | 1681.5 | 1681.5 | e12-a, clear:0 | "
                      "median <= 2 us |", host)

    def test_standard_input_gives_the_same_tables(self):
        with open(SAMPLE) as f:
            self.assertEqual(run(stdin=f.read()).stdout, self.res.stdout)


class BadInput(unittest.TestCase):
    def assert_bad(self, text, line, words):
        path, res = with_file(text)
        self.assertEqual(res.returncode, 2, res.stdout)
        self.assertEqual(res.stdout, "")
        self.assertEqual(len(res.stderr.splitlines()), 1, res.stderr)
        self.assertIn(f"{path}:{line}: ", res.stderr)
        self.assertIn(words, res.stderr)

    def test_a_missing_field_names_file_and_line(self):
        self.assert_bad("header\n" + GOOD + "M\ttarget=avr\tmode=network\tH=12\tN=32\t1\n", 3,
                        "9 tab-separated fields")

    def test_an_unknown_mode_is_named(self):
        self.assert_bad(GOOD.replace("mode=network", "mode=fast"), 1, "mode 'fast'")

    def test_an_uncounted_cortex_m4_value_is_refused(self):
        self.assert_bad(GOOD.replace("target=avr", "target=cm4").replace("120000", "-"), 1,
                        "tools/cm4-icount")

    def test_unconverted_avr_console_output_is_refused(self):
        self.assert_bad(GOOD.replace("\t", "~"), 1, "'~'")

    def test_a_non_integer_value_is_refused(self):
        self.assert_bad(GOOD.replace("120000", "12.5"), 1, "value '12.5'")

    def test_no_m_lines_is_bad_input(self):
        path, res = with_file("just text\n")
        self.assertEqual(res.returncode, 2)
        self.assertIn("no M lines", res.stderr)

    def test_a_missing_file_says_why(self):
        res = run("/nonexistent/bench.txt")
        self.assertEqual(res.returncode, 2)
        self.assertIn("/nonexistent/bench.txt: cannot open", res.stderr)


class Mismatches(unittest.TestCase):
    def test_a_mismatch_is_listed_and_fails(self):
        text = GOOD + "MISMATCH target=avr mode=table policy=e12-a N=32 scan=clear:0: heading 3, every-path step 4\n"
        path, res = with_file(text)
        self.assertEqual(res.returncode, 1)
        self.assertIn("1 heading mismatches", res.stdout)
        self.assertIn(f"{path}:2: MISMATCH target=avr mode=table", res.stdout)


class Version(unittest.TestCase):
    def test_version_is_one_line_with_the_program_name(self):
        res = run("--version")
        self.assertEqual(res.returncode, 0)
        self.assertRegex(res.stdout, r"^bench-report \(qnav\) \S+\n$")


if __name__ == "__main__":
    unittest.main()
