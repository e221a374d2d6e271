"""Issue #45 (5b, 5f): the one YAML reader of scenario files, sweep files and ``--set`` values."""

import math

import pytest

from amronet.errors import ScenarioError
from amronet.yaml_loading import MAX_DEPTH, as_bool, load_yaml


@pytest.mark.parametrize(("text", "value"), [
    ("1e-9", 1e-9), ("1E5", 1e5), ("1e300", 1e300), (".5", 0.5), ("-2.5e+3", -2500.0), ("-.5", -0.5),
    ("1.0e-9", 1e-9), ("1.5", 1.5), ("5.", 5.0), ("+3.25", 3.25), ("1_000.5", 1000.5),
])
def test_the_usual_float_notations_are_floats(text, value):
    got = load_yaml(text, "f")
    assert type(got) is float and got == value


@pytest.mark.parametrize(("text", "value"), [
    ("42", 42), ("-3", -3), ("+7", 7), ("0", 0), ("1_000", 1000), ("010", 10), ("007", 7), ("0x1F", 31), ("0o17", 15),
])
def test_integers_stay_integers_and_a_leading_zero_is_decimal(text, value):
    got = load_yaml(text, "f")
    assert type(got) is int and got == value


@pytest.mark.parametrize("text", ["0b101", "1:30", "1__0", "10_", "inf", "nan", "1e", "e5", "1.2.3"])
def test_yaml_1_1_oddities_and_non_numbers_are_strings(text):
    assert load_yaml(text, "f") == text


def test_infinities_and_nan_are_read_for_the_fields_to_refuse():
    assert load_yaml(".inf", "f") == math.inf and load_yaml("-.inf", "f") == -math.inf
    assert math.isnan(load_yaml(".nan", "f"))


@pytest.mark.parametrize(("text", "words"), [
    ("a: 1\nb: 2\na: 3\n", "f: key 'a' appears twice in 's.yaml' (lines 1 and 3); keep one"),
    ("a:\n  b: 1\n  c: 2\n  b: 3\n", "f: key 'b' appears twice in 's.yaml' (lines 2 and 4)"),
    ("{r_c: 1, r_c: 2}", "f: key 'r_c' appears twice in 's.yaml' (line 1, columns 2 and 10)"),
])
def test_a_key_given_twice_is_refused_naming_it_and_both_lines(text, words):
    with pytest.raises(ScenarioError) as info:
        load_yaml(text, "f", "'s.yaml'")
    assert str(info.value).startswith(words) and "\n" not in str(info.value)


def test_merge_keys_may_still_override():
    got = load_yaml("a: &x {k: 1, j: 2}\nb:\n  <<: *x\n  k: 3\n", "f")
    assert got == {"a": {"k": 1, "j": 2}, "b": {"k": 3, "j": 2}}


@pytest.mark.parametrize(("text", "words"), [
    ("[1", "k: the value is not valid YAML at line 1; fix the syntax"),
    ("!!float abc", "('abc' is not a number)"),
    ("!!timestamp 2020-13-45", "(month must be in 1..12)"),
    ("1" * 5000, "(an integer of 5000 digits is too long)"),
    ("[" * 3000, "is not valid YAML"),
])
def test_what_pyyaml_cannot_construct_is_one_error_line_not_a_crash(text, words):
    with pytest.raises(ScenarioError) as info:
        load_yaml(text, "k", "the value")
    assert words in str(info.value) and "\n" not in str(info.value)


@pytest.mark.parametrize(("text", "value"), [
    ("off", "off"), ("On", "On"), ("YES", "YES"), ("no", "no"), ("y", "y"), ("N", "N"), ("none", "none"),
    ("2024-05-01", "2024-05-01"), ("=", "="), ("true", True), ("True", True), ("TRUE", True), ("false", False),
    ("False", False), ("FALSE", False), ("null", None), ("~", None), ("", None), ("!!bool yes", True),
    ("{on: off, y: n, yes: 1}", {"on": "off", "y": "n", "yes": 1}),
])
def test_yaml_1_2_core_schema_only_true_and_false_are_booleans(text, value):
    """Issue #36 (2): YAML 1.1 read ``off`` as ``False``, so ``coverage_target: off`` was refused."""
    got = load_yaml(text, "f")
    assert got == value and type(got) is type(value)


@pytest.mark.parametrize(("word", "value"), [("yes", True), ("No", False), ("ON", True), ("off", False),
                                             ("y", True), ("n", False), ("true", True), ("FALSE", False),
                                             (True, True), ("maybe", "maybe"), ("1", "1"), (1, 1), (None, None)])
def test_as_bool_turns_only_the_boolean_words_into_booleans(word, value):
    got = as_bool(word)
    assert got == value and type(got) is type(value)


def _nested(levels: int, block: bool) -> str:
    if block:  # one mapping per line, indented
        return "".join("  " * i + "k:\n" for i in range(levels)) + "  " * levels + "1\n"
    return "[" * levels + "]" * levels


@pytest.mark.parametrize("block", [False, True])
def test_nesting_is_bounded_before_python_recursion_is(block):
    """Issue #36 (9d): deep nesting is refused while it is read, at a depth every later check can recurse to."""
    assert load_yaml(_nested(MAX_DEPTH, block), "f") is not None
    with pytest.raises(ScenarioError) as info:
        load_yaml(_nested(MAX_DEPTH + 1, block), "f", "'s.yaml'")
    assert str(info.value) == (f"f: 's.yaml' is not valid YAML at line {MAX_DEPTH + 1 if block else 1} (lists and "
                               f"mappings nested deeper than {MAX_DEPTH} levels); flatten it")


def _depth(value) -> int:
    return 1 + max(map(_depth, value), default=0) if isinstance(value, list) else 0


def test_aliases_cannot_nest_deeper_nor_inside_their_own_node():
    half = "[" * 60 + "]" * 60  # the document's list, then 1 + 38 lists around *x: 100 levels
    assert _depth(load_yaml(f"- &x {half}\n- [{'[' * 38}*x{']' * 38}]", "f")) == MAX_DEPTH
    with pytest.raises(ScenarioError, match=r"line 1 \(through aliases, lists and mappings nested deeper than 100"):
        load_yaml(f"- &x {half}\n- [{'[' * 39}*x{']' * 39}]", "f")
    with pytest.raises(ScenarioError, match=r"\(alias \*a stands inside the node it names\); name another node"):
        load_yaml("a: &a {b: [*a]}", "f")
    assert load_yaml("a: &a [1]\nb: [*a, *a]", "f") == {"a": [1], "b": [[1], [1]]}
