#!/usr/bin/env python3
"""Writes the corpus of bad policy files in tests/policyio/bad/ and its side table
bad/expected.tsv (file, line the reader must name, fragment its message must contain).
Each file breaks one rule of docs/policy-format.md. Run from anywhere:
    python3 tests/policyio/make_bad_corpus.py
The files are committed; test_policy_io.c reads them and the side table."""
import os

HERE = os.path.dirname(os.path.abspath(__file__))
BAD = os.path.join(HERE, "bad")

NET = (
    "qnav-policy 1\n"                     # 1
    "kind network\n"                      # 2
    "qformat Q8.8\n"                      # 3
    "hidden 3\n"                          # 4
    "unit 0 -512 300 12 -40\n"            # 5
    "unit 1 256 -128 0 1024\n"            # 6
    "unit 2 7 2560 -256 3\n"              # 7
    "b_out 64\n"                          # 8
    "end\n"                               # 9
)
PROB = (
    "qnav-policy 1\n"                     # 1
    "kind probabilistic\n"                # 2
    "qformat Q8.8\n"                      # 3
    "k_goal 512\n"                        # 4
    "k_safe 1536\n"                       # 5
    "end\n"                               # 6
)


def replace_line(base, n, text):
    """base with line n (1-based) replaced by text (None deletes it)."""
    lines = base.splitlines(keepends=True)
    if text is None:
        del lines[n - 1]
    else:
        lines[n - 1] = text
    return "".join(lines)


def net_line(n, text):
    return replace_line(NET, n, text)


def net_insert(n, text):
    """NET with text inserted before line n."""
    lines = NET.splitlines(keepends=True)
    lines.insert(n - 1, text)
    return "".join(lines)


def prob_line(n, text):
    return replace_line(PROB, n, text)


CASES = [
    # name, content (str or bytes), line, fragment
    ("empty", "", 1, "empty file"),
    ("only_magic", "qnav-policy 1\n", 1, "truncated: no 'end' line"),
    ("bad_magic", NET.replace("qnav-policy 1", "qnav-polcy 1"), 1, "not a qnav policy file"),
    ("comment_before_magic", "# a policy\n" + NET, 1, "not a qnav policy file"),
    ("version_3", NET.replace("qnav-policy 1", "qnav-policy 3"), 1,
     "unsupported format version 3"),
    ("version_2_unit_before_inputs", NET.replace("qnav-policy 1", "qnav-policy 2"), 5,
     "'unit' before 'inputs'"),
    ("version_2_inputs_four", net_insert(5, "inputs 4\n").replace("qnav-policy 1", "qnav-policy 2"),
     5, "inputs '4': a network has 2 or 3 inputs"),
    ("version_2_inputs_three_four_weights",
     net_insert(5, "inputs 3\n").replace("qnav-policy 1", "qnav-policy 2"), 6,
     "unit 0: expected 5 weights (w_theta w_dist w_prev b_hidden w_out), found 4"),
    ("version_1_with_inputs", net_insert(5, "inputs 3\n"), 5, "unknown key 'inputs'"),
    ("prob_with_inputs", prob_line(4, "inputs 3\n").replace("qnav-policy 1", "qnav-policy 2"),
     4, "'inputs' is not a key of kind probabilistic"),
    ("version_not_integer", NET.replace("qnav-policy 1", "qnav-policy one"), 1,
     "format version 'one' is not an integer"),
    ("byte_order_mark", b"\xef\xbb\xbf" + NET.encode(), 1, "byte order mark"),
    ("unknown_kind", net_line(2, "kind tree\n"), 2, "unknown kind 'tree'"),
    ("kind_not_first", net_insert(2, "qformat Q8.8\n"), 2,
     "expected 'kind' as the first key, found 'qformat'"),
    ("kind_without_value", net_line(2, "kind\n"), 2, "'kind' takes 1 value, found 0"),
    ("duplicate_kind", net_insert(4, "kind network\n"), 4, "duplicate 'kind' (first on line 2)"),
    ("duplicate_hidden", net_insert(5, "hidden 3\n"), 5, "duplicate 'hidden' (first on line 4)"),
    ("hidden_zero", net_line(4, "hidden 0\n"), 4, "hidden 0 outside 1..32"),
    ("hidden_too_many", net_line(4, "hidden 33\n"), 4, "hidden 33 outside 1..32"),
    ("hidden_not_integer", net_line(4, "hidden three\n"), 4, "hidden 'three' is not an integer"),
    ("qformat_other", net_line(3, "qformat Q1.15\n"), 3, "unsupported qformat 'Q1.15'"),
    ("missing_qformat", net_line(3, None), 8, "missing 'qformat'"),
    ("unit_three_weights", net_line(6, "unit 1 256 -128 0\n"), 6,
     "unit 1: expected 4 weights (w_theta w_dist b_hidden w_out), found 3"),
    ("unit_five_weights", net_line(6, "unit 1 256 -128 0 1024 9\n"), 6,
     "unit 1: expected 4 weights (w_theta w_dist b_hidden w_out), found 5"),
    ("weight_decimal", net_line(5, "unit 0 -512 1.5 12 -40\n"), 5,
     "unit 0: '1.5' is not an integer"),
    ("weight_hex", net_line(7, "unit 2 7 0x10 -256 3\n"), 7, "unit 2: '0x10' is not an integer"),
    ("weight_above_int16", net_line(6, "unit 1 256 -128 32768 1024\n"), 6,
     "unit 1: value 32768 outside the Q8.8 range -32768..32767"),
    ("weight_below_int16", net_line(5, "unit 0 -32769 300 12 -40\n"), 5,
     "unit 0: value -32769 outside the Q8.8 range"),
    ("weight_huge", net_line(5, "unit 0 -512 300 12 99999999999999999999\n"), 5,
     "value 99999999999999999999 outside the Q8.8 range"),
    ("b_out_not_integer", net_line(8, "b_out 6e4\n"), 8, "b_out: '6e4' is not an integer"),
    ("unit_before_hidden", "qnav-policy 1\nkind network\nqformat Q8.8\nunit 0 1 2 3 4\n"
     "hidden 1\nb_out 0\nend\n", 4, "'unit' before 'hidden'"),
    ("unit_out_of_order", net_line(6, "unit 2 7 2560 -256 3\n"), 6,
     "unit 2 out of order: expected unit 1"),
    ("unit_duplicate", net_insert(6, "unit 0 -512 300 12 -40\n"), 6,
     "duplicate unit 0 (first on line 5)"),
    ("unit_index_too_big", net_insert(8, "unit 3 1 1 1 1\n"), 8, "unit 3 outside 0..2 (hidden 3)"),
    ("missing_unit", net_line(7, None), 8, "missing unit 2 (hidden 3 needs units 0..2)"),
    ("missing_b_out", net_line(8, None), 8, "missing 'b_out'"),
    ("missing_hidden_and_units", "qnav-policy 1\nkind network\nqformat Q8.8\nb_out 0\nend\n", 5,
     "missing 'hidden'"),
    ("missing_end", net_line(9, None), 8, "truncated: no 'end' line"),
    ("truncated_mid_line", NET[: NET.index("unit 2") + len("unit 2 7 25")], 7,
     "unit 2: expected 4 weights (w_theta w_dist b_hidden w_out), found 2"),
    ("end_with_value", net_line(9, "end now\n"), 9, "'end' takes no values"),
    ("trailing_garbage", NET + "unit 3 0 0 0 0\n", 10, "content after 'end' (line 9)"),
    ("long_line", net_insert(5, "# " + "x" * 300 + "\n"), 5, "line longer than 256 bytes"),
    ("nul_byte", NET.replace("unit 1 256", "unit 1 2\x0056").encode(), 6, "NUL byte at column 9"),
    ("lone_carriage_return", net_line(6, "unit 1 256\r-128 0 1024\n"), 6,
     "carriage return not followed by a line feed at column 11"),
    ("control_character", net_insert(3, "# bell \x07 here\n"), 3, "control character 0x07 at column 8"),
    ("too_many_tokens", net_line(6, "unit 1 256 -128 0 1024 1 2 3 4 5\n"), 6, "too many values"),
    ("unknown_key", net_insert(8, "w_extra 12\n"), 8, "unknown key 'w_extra'"),
    ("net_with_k_goal", net_insert(8, "k_goal 512\n"), 8, "'k_goal' is not a key of kind network"),
    ("prob_with_hidden", prob_line(4, "hidden 3\n"), 4,
     "'hidden' is not a key of kind probabilistic"),
    ("prob_k_goal_zero", prob_line(4, "k_goal 0\n"), 4, "k_goal 0 outside (0, 64]"),
    ("prob_k_goal_negative", prob_line(4, "k_goal -256\n"), 4, "k_goal -256 outside (0, 64]"),
    ("prob_k_safe_above_64", prob_line(5, "k_safe 16385\n"), 5, "k_safe 16385 outside (0, 64]"),
    ("prob_missing_k_safe", prob_line(5, None), 5, "missing 'k_safe'"),
    ("prob_duplicate_k_goal", prob_line(5, "k_goal 512\n"), 5,
     "duplicate 'k_goal' (first on line 4)"),
    ("meta_duplicate", net_insert(5, "meta source a\nmeta source b\n"), 6,
     "duplicate meta 'source' (first on line 5)"),
    ("meta_bad_name", net_insert(5, "meta bad/name x\n"), 5, "meta name 'bad/name'"),
    ("meta_without_value", net_insert(5, "meta fitness   # none\n"), 5,
     "'meta' needs a name and a value"),
]


def main():
    os.makedirs(BAD, exist_ok=True)
    for f in os.listdir(BAD):
        if f.endswith(".policy"):
            os.remove(os.path.join(BAD, f))
    rows = ["# file\tline\tfragment of the one-line error (made by ../make_bad_corpus.py)"]
    for name, content, line, frag in CASES:
        data = content if isinstance(content, bytes) else content.encode()
        with open(os.path.join(BAD, name + ".policy"), "wb") as fh:
            fh.write(data)
        rows.append("%s.policy\t%d\t%s" % (name, line, frag))
    with open(os.path.join(BAD, "expected.tsv"), "w") as fh:
        fh.write("\n".join(rows) + "\n")
    print("wrote %d bad files to %s" % (len(CASES), BAD))


if __name__ == "__main__":
    main()
