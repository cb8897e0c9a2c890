"""tools/cm4-icount on icount_regions.c: every region's count equals the one derived from its
assembly (the program prints it beside the `-`), two runs agree, the program's exit status
is passed on, and bad input or a failed run gives one line on stderr and status 2 or 1.
A fake QEMU writing a given log checks the rare log lines (a TB stopped before it ran) and a
log the counter cannot read. Run by CTest from the cm4 build (tests/target/CMakeLists.txt)."""
import os
import stat
import subprocess
import sys
import tempfile
import unittest

TOOL = os.environ["ICOUNT_TOOL"]
REGIONS = os.environ["ICOUNT_REGIONS_ELF"]        # icount_regions.c, variant 0
VARIANT = os.environ["ICOUNT_VARIANT_ELF"]        # the same with "%d" for variants 1..4
NO_MARKERS = os.environ["ICOUNT_NO_MARKERS_ELF"]  # a cm4 program without the markers
NM = os.environ.get("ICOUNT_NM", "arm-none-eabi-nm")
VERSION_FILE = os.environ["ICOUNT_VERSION_FILE"]

# name and expected count of each result line, in order, as icount_regions.c's assembly gives
EXPECTED = [("empty", 1), ("straight", 11), ("loop", 3), ("loop", 21), ("loop", 5001),
            ("loop", 300001), ("calls", 14), ("it_taken", 5), ("it_skipped", 5),
            ("long_block", 1501), ("ram_4", 7), ("ram_40", 43), ("ram_4_again", 7)]


def icount(*args):
    return subprocess.run([TOOL, "--nm", NM, "--timeout", "600", *args],
                          capture_output=True, text=True, timeout=900)


def results(stdout):
    """(name, expected, counted) of each M line but the header."""
    rows = [line.split("\t") for line in stdout.splitlines() if line.startswith("M\t")]
    return [(r[1], int(r[2]), r[3]) for r in rows[1:]]


def assert_one_line_error(case, r, status, *words):
    case.assertEqual(r.returncode, status, r.stderr)
    case.assertEqual(r.stdout, "")
    lines = r.stderr.splitlines()
    case.assertEqual(len(lines), 1, r.stderr)
    for w in words:
        case.assertIn(w, lines[0])


class Counts(unittest.TestCase):
    def test_each_region_counts_the_instructions_of_its_assembly(self):
        r = icount(REGIONS)
        self.assertEqual(r.returncode, 0, r.stderr)
        got = results(r.stdout)
        self.assertEqual([(n, e) for n, e, _ in got], EXPECTED)
        for name, expected, counted in got:
            self.assertEqual(counted, str(expected), name)

    def test_lines_other_than_results_are_printed_unchanged(self):
        lines = icount(REGIONS).stdout.splitlines()
        self.assertEqual(lines[0], "icount_regions: regions of known instruction counts")
        self.assertEqual(lines[1], "M\tregion\texpected\tcount")
        self.assertEqual(lines[-1], f"icount_regions: {len(EXPECTED)} results")
        self.assertEqual(len(lines), len(EXPECTED) + 3)

    def test_two_runs_give_identical_output(self):
        a, b = icount(REGIONS), icount(REGIONS)
        self.assertEqual(a.returncode, 0, a.stderr)
        self.assertEqual(a.stdout, b.stdout)

    def test_the_program_exit_status_is_passed_on(self):
        r = icount(VARIANT % 3)
        self.assertEqual(r.returncode, 3, r.stderr)
        self.assertEqual([c for _, _, c in results(r.stdout)], [str(e) for _, e in EXPECTED])


class BadInput(unittest.TestCase):
    def test_more_result_lines_than_regions_is_bad_input(self):
        elf = VARIANT % 1
        assert_one_line_error(self, icount(elf), 2, elf, "14 result lines", "13 ")

    def test_fewer_result_lines_than_regions_is_bad_input(self):
        elf = VARIANT % 2
        assert_one_line_error(self, icount(elf), 2, elf, "13 result lines", "14 ")

    def test_a_program_without_markers_is_bad_input(self):
        assert_one_line_error(self, icount(NO_MARKERS), 2, NO_MARKERS, "qnav_bench_begin",
                              "qnav_bench_end")

    def test_a_file_that_is_not_an_elf_is_bad_input(self):
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "notes.elf")
            with open(path, "w") as f:
                f.write("not a program\n")
            assert_one_line_error(self, icount(path), 2, path, "not an ELF file")

    def test_a_missing_file_is_bad_input(self):
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "none.elf")
            assert_one_line_error(self, icount(path), 2, path, "cannot open")

    def test_no_program_is_bad_usage(self):
        r = icount()
        self.assertEqual(r.returncode, 2)
        self.assertIn("usage:", r.stderr)


class RunFailures(unittest.TestCase):
    def test_a_program_that_locks_the_core_up_is_a_run_failure(self):
        elf = VARIANT % 4
        assert_one_line_error(self, icount(elf), 1, elf, "QEMU stopped after 13 regions",
                              "Lockup")

    def test_a_qemu_that_cannot_be_run_is_a_run_failure(self):
        with tempfile.TemporaryDirectory() as d:
            r = icount("--qemu", os.path.join(d, "no-qemu"), REGIONS)
            assert_one_line_error(self, r, 1, REGIONS, "cannot run")

    def test_a_run_past_the_timeout_is_a_run_failure(self):
        r = subprocess.run([TOOL, "--nm", NM, "--timeout", "0.001", REGIONS],
                           capture_output=True, text=True, timeout=900)
        assert_one_line_error(self, r, 1, REGIONS, "no exit within 0.001 s")


def begin_end_addresses():
    out = subprocess.run([NM, REGIONS], capture_output=True, text=True, check=True).stdout
    syms = {f[2]: int(f[0], 16) for f in (ln.split() for ln in out.splitlines()) if len(f) == 3}
    return syms["qnav_bench_begin"], syms["qnav_bench_end"]


def block(pc, *halfwords):
    """An in_asm block of 16-bit instructions at pc."""
    lines = ["----------------\n", "IN: fake\n"]
    for i, hw in enumerate(halfwords):
        lines.append(f"0x{pc + 2 * i:08x}:  {hw}       insn\n")
    return "".join(lines) + "\n"


def trace(ptr, pc):
    return f"Trace 0: 0x{ptr:x} [00800408/{pc:08x}/00000110/ff000200] fake\n"


class FakeQemuLog(unittest.TestCase):
    """cm4-icount on logs written by a stand-in for qemu-system-arm."""

    def run_fake(self, log, stdout):
        with tempfile.TemporaryDirectory() as d:
            for name, text in (("log", log), ("stdout", stdout)):
                with open(os.path.join(d, name), "w") as f:
                    f.write(text)
            fake = os.path.join(d, "qemu")
            with open(fake, "w") as f:
                f.write(f"#!{sys.executable}\n"
                        "import sys\n"
                        "log = sys.argv[sys.argv.index('-D') + 1]\n"
                        f"open(log, 'w').write(open({os.path.join(d, 'log')!r}).read())\n"
                        f"sys.stdout.write(open({os.path.join(d, 'stdout')!r}).read())\n")
            os.chmod(fake, stat.S_IRWXU)
            return icount("--qemu", fake, REGIONS)

    def test_a_tb_stopped_before_it_ran_is_not_counted(self):
        b, e = begin_end_addresses()
        log = (block(b, "4770") + trace(0x1000, b)
               + block(0x400, "2001", "2002", "2003") + trace(0x1100, 0x400)
               + trace(0x1100, 0x400) + "Stopped execution of TB chain before 0x1100 "
               "[00000400] fake\n"
               + block(e, "4770") + trace(0x1200, e)
               + "Stopped execution of TB chain before 0x1200 [%08x] fake\n" % e
               + trace(0x1200, e))
        r = self.run_fake(log, "M\tx\t-\n")
        self.assertEqual((r.returncode, r.stdout), (0, "M\tx\t3\n"), r.stderr)

    def test_a_retranslated_tb_counts_its_new_length(self):
        b, e = begin_end_addresses()
        log = (block(b, "4770") + trace(0x1000, b)
               + block(0x400, "2001", "2002") + trace(0x1100, 0x400)
               + block(0x400, "2001", "2002", "2003", "2004") + trace(0x1100, 0x400)
               + trace(0x1100, 0x400) + block(e, "4770") + trace(0x1200, e))
        r = self.run_fake(log, "M\tx\t-\n")
        self.assertEqual((r.returncode, r.stdout), (0, "M\tx\t10\n"), r.stderr)

    def test_a_begin_inside_a_region_is_bad_input(self):
        b, _ = begin_end_addresses()
        log = block(b, "4770") + trace(0x1000, b) + trace(0x1000, b)
        assert_one_line_error(self, self.run_fake(log, ""), 2, REGIONS,
                              "qnav_bench_begin called again before qnav_bench_end")

    def test_an_end_outside_a_region_is_bad_input(self):
        _, e = begin_end_addresses()
        log = block(e, "4770") + trace(0x1200, e)
        assert_one_line_error(self, self.run_fake(log, ""), 2, REGIONS,
                              "qnav_bench_end called without qnav_bench_begin")

    def test_a_disassembly_that_disagrees_with_the_translator_is_a_run_failure(self):
        log = (block(0x400, "2001") + trace(0x1100, 0x400)
               + "Disassembler disagrees with translator over instruction decoding\n")
        assert_one_line_error(self, self.run_fake(log, ""), 1, REGIONS, "QEMU log",
                              "Disassembler disagrees")

    def test_a_tb_never_translated_is_a_run_failure(self):
        assert_one_line_error(self, self.run_fake(trace(0x1100, 0x400), ""), 1, REGIONS,
                              "never translated")


class CommandLine(unittest.TestCase):
    def test_help_exits_0_and_names_the_markers(self):
        r = subprocess.run([TOOL, "--help"], capture_output=True, text=True)
        self.assertEqual(r.returncode, 0)
        self.assertIn("usage: cm4-icount", r.stdout)
        self.assertIn("qnav_bench_begin", r.stdout)

    def test_version_is_one_line_with_the_version_file(self):
        with open(VERSION_FILE) as f:
            v = f.readline().strip()
        r = subprocess.run([TOOL, "--version"], capture_output=True, text=True)
        self.assertEqual((r.returncode, r.stdout), (0, f"cm4-icount (qnav) {v}\n"))


if __name__ == "__main__":
    unittest.main()
