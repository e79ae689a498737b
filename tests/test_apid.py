"""The bit-climbing GA."""

import pytest

from hesspipe.core.errors import HesspipeError
from hesspipe.identification.apid import Field, bit_climb, gray_to_int, int_to_gray


def test_field_decoding_and_bounds():
    f = Field("Ke", 11)
    assert (f.lo, f.hi) == (0.0, 20.47)
    assert Field("K1", 10).hi == pytest.approx(10.23)
    g = Field("x", 11, 100.0, -10.24)  # the paper's negative range
    assert g.lo == pytest.approx(-10.24) and g.hi == pytest.approx(10.23)
    assert f.decode(f.encode(12.346)) == pytest.approx(12.35)
    f.check_within(0.0, 20.47)
    with pytest.raises(HesspipeError, match="bit field 'Ke'.*spans 0..20.47.*bounds 0..10"):
        f.check_within(0.0, 10.0)
    with pytest.raises(HesspipeError, match="bits"):
        Field("x", 0)
    with pytest.raises(HesspipeError, match="scale"):
        Field("x", 10, scale=0.0)


def test_gray_code_roundtrip_and_adjacency():
    for n in range(2048):
        assert gray_to_int(int_to_gray(n)) == n
        if n:
            assert bin(int_to_gray(n) ^ int_to_gray(n - 1)).count("1") == 1


def _quadratic(target):
    def f(v):
        return sum((v[k] - t) ** 2 for k, t in target.items())
    return f


@pytest.mark.parametrize("coding", ["binary", "gray"])
def test_climb_is_seeded_and_keeps_full_history(coding):
    fields = [Field("a", 10), Field("b", 10)]
    obj = _quadratic({"a": 3.21, "b": 7.0})
    r1 = bit_climb(obj, fields, passes=10, seed=5, coding=coding)
    r2 = bit_climb(obj, fields, passes=10, seed=5, coding=coding)
    assert r1 == r2
    assert r1.evaluations == len(r1.history) == 1 + 20 * r1.passes
    # Each pass flips every bit exactly once.
    for p in range(1, r1.passes + 1):
        bits = sorted(h.bit for h in r1.history if h.pass_ == p)
        assert bits == list(range(20))
    # Stops after the first pass without an improvement (or the budget).
    last = [h for h in r1.history if h.pass_ == r1.passes]
    assert r1.passes == 10 or not any(h.accepted for h in last)
    accepted = [h.fitness for h in r1.history if h.accepted]
    assert accepted == sorted(accepted, reverse=True) and r1.fitness == accepted[-1]
    assert r1.best_so_far()[-1] == r1.fitness
    r3 = bit_climb(obj, fields, passes=10, seed=6, coding=coding)
    assert r3.initial != r1.initial


def test_gray_climb_finds_a_separable_optimum():
    # With Gray coding neighbouring values are one flip apart, so a separable
    # convex objective is climbed to the grid optimum from any start.
    fields = [Field("a", 10), Field("b", 10, 100.0, -5.0)]
    obj = _quadratic({"a": 3.21, "b": -1.5})
    for seed in range(5):
        r = bit_climb(obj, fields, passes=50, seed=seed, coding="gray")
        assert r.values == {"a": pytest.approx(3.21), "b": pytest.approx(-1.5)}


def test_pass_budget_and_bad_objective():
    fields = [Field("a", 10)]
    r = bit_climb(_quadratic({"a": 5.0}), fields, passes=1, seed=0)
    assert r.passes == 1 and r.evaluations == 11
    with pytest.raises(HesspipeError, match="non-finite"):
        bit_climb(lambda v: float("nan"), fields)
    with pytest.raises(HesspipeError, match="passes"):
        bit_climb(_quadratic({"a": 1.0}), fields, passes=0)
    with pytest.raises(HesspipeError, match="twice"):
        bit_climb(_quadratic({"a": 1.0}), fields * 2)
