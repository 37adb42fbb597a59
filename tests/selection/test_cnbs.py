"""CNBS, global version: heat map pieces against brute force, greedy choice against exact σ."""

import math

import numpy as np
import pytest

from shapecond.selection.cnbs import CNBSOptions, HeatMap, HeatMapOptions, cnbs_landmarks, heat_map, repair_fixing
from shapecond.selection.swap_floor import best_swap_avoiding, swap_floor, swap_scores
from shapecond.symmetry.exact import exact_sigma
from shapecond.symmetry.objective import map_score

from tests.helpers import mirror_pairs_instance


def _dist(P):
    D = np.linalg.norm(P[:, None] - P[None], axis=2)
    return D / D.max()


def test_swap_scores_match_map_score():
    rng = np.random.default_rng(3)
    D = _dist(rng.normal(size=(9, 3)))
    for n in (9, 6):  # bijections, and dense targets (samples = first 6 of 9)
        S = swap_scores(D, n)
        for a in range(n):
            for b in range(n):
                if a != b:
                    t = np.arange(n)
                    t[a], t[b] = b, a
                    assert math.isclose(S[a, b], map_score(D, t), rel_tol=1e-9)


def test_swap_of_an_isometry_is_inf():
    # square: swapping two opposite corners... is not an isometry; a 2-point space is
    D = np.array([[0.0, 1.0, 0.5], [1.0, 0.0, 0.5], [0.5, 0.5, 0.0]])
    assert swap_scores(D, 3)[0, 1] == np.inf


def test_best_swap_avoiding_brute_force():
    rng = np.random.default_rng(4)
    D = _dist(rng.normal(size=(10, 3)))
    S = swap_scores(D, 10)
    fixed = [2]
    cand = [p for p in range(10) if p not in fixed]
    got = best_swap_avoiding(S, fixed, cand)
    for p, g in zip(cand, got):
        bad = set(fixed) | {p}
        want = max(S[a, b] for a in range(10) for b in range(10) if a != b and a not in bad and b not in bad)
        assert math.isclose(g, want, rel_tol=1e-12)


def test_repair_fixing_one_move():
    rng = np.random.default_rng(5)
    for _ in range(50):
        n, m = 8, 12
        t = rng.choice(m, n, replace=False)
        p = int(rng.integers(n))
        r = repair_fixing(t, p)
        assert r[p] == p and len(set(r.tolist())) == n
        assert np.sum(r != t) <= 2


@pytest.mark.parametrize("prune", [False, True])
def test_heat_map_is_a_bracketed_lower_bound(prune):
    """Each value is a σ of a feasible map (<= exact σ with p fixed) and >= the swap floor."""
    for seed in range(6):
        D = mirror_pairs_instance(7, seed)
        hm = heat_map(D, 7, landmarks=[], options=HeatMapOptions(seed=seed, prune=prune))
        S = swap_scores(D, 7)
        for p in range(7):
            ex = exact_sigma(D, 7, landmarks=[p]).sigma
            assert hm.values[p] <= ex * (1 + 1e-9)
            floor = best_swap_avoiding(S, [], [p])[0]
            assert hm.values[p] >= floor * (1 - 1e-12)
            if hm.results.get(p) is not None and hm.values[p] == hm.results[p].sigma:
                w = hm.results[p].witness
                assert w[p] == p and math.isclose(map_score(D, w), hm.values[p], rel_tol=1e-9)


@pytest.mark.parametrize("seed", range(4))
def test_greedy_choice_equals_exact_argmin(seed):
    """For 3 steps, the CNBS landmark has the smallest exact σ among the candidates."""
    n = 8
    D = mirror_pairs_instance(n, 10 + seed, noise=0.05)
    out = cnbs_landmarks(D, n, 3, options=CNBSOptions(seed=0))
    L = []
    for c, score in zip(out["landmarks"], out["scores"]):
        exact = {p: exact_sigma(D, n, landmarks=L + [p]).sigma for p in range(n) if p not in L}
        best = min(exact.values())
        assert exact[c] <= best * (1 + 1e-6), (L, c, exact)
        assert math.isclose(score, exact[c], rel_tol=1e-6)
        L.append(c)


def test_argmin_tie_breaks_by_move_then_index():
    hm = HeatMap(np.array([np.nan, 1.0, 1.0, 2.0]), 3.0, (0,), np.array([0.0, 0.2, 0.5, 0.9]),
                 np.zeros(4, bool))
    assert hm.argmin() == 2
    assert list(hm.improvement()[1:]) == [2.0, 2.0, 1.0]


def test_animal_first_landmark_off_the_mirror_plane():
    """On the near-symmetric animal (N = 100) the first CNBS landmark is off the mirror plane: the
    mirror fixes the samples on the plane, so fixing one of them lowers σ least."""
    from shapecond.shapes.metric import Sampling, build_metric_shape
    from shapecond.shapes.synthetic import animal

    g = animal(delta=0.05)
    shape = build_metric_shape(g, n_points=100, sampling=Sampling(cache=False))
    x = np.abs(g.vertices[shape.samples[:100], 0])
    on_plane = x < 1e-9
    assert on_plane.sum() >= 3
    hm = heat_map(shape.D, 100, options=HeatMapOptions(seed=0))
    c = hm.argmin()
    assert not on_plane[c]
    imp = hm.improvement()
    # samples on the mirror plane are fixed by the mirror witness: no improvement,
    # the smallest of all candidates
    assert np.allclose(imp[on_plane], 0.0)
    assert imp[on_plane].max() <= np.nanmin(imp[~on_plane]) + 1e-12
    assert hm.values[c] < hm.sigma_before


@pytest.mark.parametrize("seed", range(5))
def test_pruned_heat_map_keeps_the_argmin(seed):
    """Pruning stops searches above the incumbent: same argmin, values still lower bounds."""
    n = 16
    D = mirror_pairs_instance(n, 40 + seed, noise=0.04)
    full = heat_map(D, n, options=HeatMapOptions(seed=0))
    cut = heat_map(D, n, options=HeatMapOptions(seed=0, prune=True))
    c = cut.argmin()
    assert cut.pruned.any()  # otherwise this test tests nothing
    assert not cut.pruned[c]
    assert math.isclose(cut.values[c], full.values[full.argmin()], rel_tol=1e-9)
    # a pruned candidate stopped above the leader's value: it could not be the argmin
    assert np.all(cut.values[cut.pruned] >= cut.values[c])
    for p in np.flatnonzero(cut.pruned):
        w = cut.results[p].witness if p in cut.results else None
        if w is not None and cut.values[p] == cut.results[p].sigma:
            assert w[p] == p and math.isclose(map_score(D, w), cut.values[p], rel_tol=1e-9)


@pytest.mark.parametrize("max_verify", [0, 1, 3])
def test_pruned_heat_map_never_returns_a_pruned_argmin(max_verify):
    """Whatever the verification budget, the argmin is a fully evaluated candidate with a witness."""
    for seed in range(4):
        D = mirror_pairs_instance(18, 60 + seed, noise=0.05)
        hm = heat_map(D, 18, options=HeatMapOptions(seed=0, prune=True, max_verify=max_verify))
        c = hm.argmin()
        assert not hm.pruned[c] and c in hm.results


@pytest.mark.parametrize("budget", [None, "scale"])
def test_heat_map_is_the_same_in_one_thread_and_in_two(budget):
    """Candidates run in parallel threads in chunks of ``CHUNK`` against the incumbent of the chunks
    before, with kicks seeded by (seed, candidate): the values, pruned or not, cannot depend on the
    thread count."""
    import numba

    from shapecond.symmetry.scale import budget_of, default_epsilon

    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("numba has one thread on this machine")
    D = mirror_pairs_instance(60, 4, noise=0.05)
    b = None if budget is None else budget_of(default_epsilon(D), 60, D)
    out = []
    before = numba.get_num_threads()
    try:
        for k in (1, 2):
            numba.set_num_threads(k)
            out.append([heat_map(D, 60, [3], budget=b, options=HeatMapOptions(effort="quick", prune=prune)).values for prune in (False, True)])
    finally:
        numba.set_num_threads(before)
    for a, c in zip(*out):
        np.testing.assert_array_equal(a, c)


def test_cnbs_options_are_one_object_and_the_interface_takes_their_fields():
    from shapecond.selection import method_options
    from shapecond.errors import InputError

    D = mirror_pairs_instance(24, 5)
    a = cnbs_landmarks(D, 24, 2, options=CNBSOptions(seed=1, effort="quick", n_kicks=2, n_cross=4, max_verify=1))
    assert len(a["landmarks"]) == 2 and len(a["scores"]) == 2
    assert {"n_kicks", "n_cross", "max_verify", "resolve_fraction"} <= method_options("cnbs")
    with pytest.raises(InputError):
        CNBSOptions(resolve="sometimes")
    with pytest.raises(TypeError):  # one call form: a field is not a keyword of the function
        heat_map(D, 24, n_kicks=2)
    with pytest.raises(TypeError):
        HeatMapOptions(n_kick=2)


def test_cut_verifications_choose_what_full_ones_do(monkeypatch):
    """CNBS-scale's verifications stop once the leader passes the runner-up (or the tie window) and are
    completed from their start when they matter again, and each donor map is searched once: the
    landmarks and the scores are those of verifications run in full from every donor."""
    from shapecond.selection import cnbs
    from shapecond.symmetry.scale import budget_of, default_epsilon

    verify, complete = cnbs._HeatMapRun.verify, cnbs._HeatMapRun.complete
    calls = {"cut": 0, "complete": 0}

    def counted_verify(self, c, stop=math.inf, count=True):
        cut = verify(self, c, stop, count)
        calls["cut"] += cut
        return cut

    def counted_complete(self, c, stop=math.inf):
        calls["complete"] += 1
        complete(self, c, stop)

    for seed in range(4):
        n = 36
        D = mirror_pairs_instance(n, 80 + seed, noise=0.06)
        kw = {"budget": budget_of(default_epsilon(D, n), n, D), "options": CNBSOptions(effort="quick", n_cross=8)}
        with monkeypatch.context() as m:
            m.setattr(cnbs._HeatMapRun, "verify", counted_verify)
            m.setattr(cnbs._HeatMapRun, "complete", counted_complete)
            got = cnbs_landmarks(D, n, 4, **kw)
        with monkeypatch.context() as m:
            m.setattr(cnbs._HeatMapRun, "verify",  # never cut
                      lambda self, c, stop=math.inf, count=True: verify(self, c, count=count))
            m.setattr(cnbs, "distinct_maps", list)
            want = cnbs_landmarks(D, n, 4, **kw)
        assert got["landmarks"] == want["landmarks"] and got["scores"] == want["scores"]
    assert calls["cut"] and calls["complete"]  # otherwise this test tests nothing


def _plane_points(n, seed):
    p = np.random.default_rng(seed).uniform(size=(n, 2))
    return _dist(p)


def _feasible_for(D, t, landmarks, budget):
    """``t`` is a map of δ(ε)'s problem with ``landmarks`` fixed: it fixes them, stays within the Dist²
    budget and keeps every landmark row within budget / N (``symmetry.scale``)."""
    from shapecond.symmetry import objective as obj

    n = len(t)
    return (all(t[landmarks] == landmarks) and obj.dist2(D, t) <= budget
            and float(np.max(obj.anchor_rows(D, t, landmarks))) <= budget / n)


# (seed, ε in units of the sample spacing, landmarks): instances where, before the fix, a candidate
# was credited the previous map, which fixes it but breaks its row budget (seeds 1 and 4), or given a
# single-swap floor that breaks a landmark's or its own row budget (seeds 0 and 2)
_ROW_CASES = [(1, 1.0, 1), (4, 0.5, 1), (0, 2.0, 2), (2, 0.5, 1)]


@pytest.mark.parametrize("prune", [False, True])
@pytest.mark.parametrize("seed, factor, n_landmarks", _ROW_CASES)
def test_scale_heat_values_are_lower_bounds_of_each_candidates_problem(seed, factor, n_landmarks, prune):
    """On δ(ε) (a budget) each heat value is at most the exact optimum of the problem with the candidate
    added as a landmark, its distance row's budget included (enumeration of every map, N = 7), and the
    search result credited to a candidate attains its value with a map feasible for that problem."""
    from shapecond.symmetry.scale import budget_of, default_epsilon
    from tests.helpers import brute_delta

    n = 7
    D = _plane_points(n, seed)
    eps = factor * default_epsilon(D)
    budget = budget_of(eps, n, D)
    L = list(range(n_landmarks))
    hm = heat_map(D, n, L, budget=budget, options=HeatMapOptions(effort="quick", prune=prune))
    for p in range(n_landmarks, n):
        exact = brute_delta(D, eps, L + [p]) * math.sqrt(n)  # heat values are sqrt(d²) = sqrt(N)·δ
        assert hm.values[p] <= exact + 1e-9, (p, hm.values[p], exact)
        r = hm.results.get(p)
        if r is not None:
            assert _feasible_for(D, np.asarray(r.witness), L + [p], budget), p


def test_scale_heat_map_credits_the_previous_map_only_within_the_candidates_row_budget():
    """The previous step's map fixes candidate 4 but distorts its distances beyond the row budget that
    fixing 4 adds: crediting it gave 4 the previous value (1.440), above the exact optimum (1.165)."""
    from shapecond.symmetry import objective as obj
    from shapecond.symmetry.scale import budget_of, default_epsilon
    from shapecond.symmetry.search import witness_search
    from tests.helpers import brute_delta

    n, p = 7, 4
    D = _plane_points(n, 1)
    eps = default_epsilon(D)
    budget = budget_of(eps, n, D)
    base = witness_search(D, n, [0], effort="quick", budget=budget)
    prev = np.asarray(base.witness)
    assert prev[p] == p and obj.anchor_rows(D, prev, [p])[0] > budget / n  # the premise
    hm = heat_map(D, n, [0], base=base, budget=budget, options=HeatMapOptions(effort="quick"))
    assert hm.values[p] <= brute_delta(D, eps, [0, p]) * math.sqrt(n) + 1e-9
    assert hm.values[p] < base.sigma and _feasible_for(D, np.asarray(hm.results[p].witness), [0, p], budget)


def test_scale_swap_floor_brute_force():
    """With a budget the floor of each candidate p is the widest single swap of the problem with p added
    as a landmark: within the Dist² budget, every landmark's row and p's row within budget / N."""
    from shapecond.symmetry import objective as obj
    from shapecond.symmetry.scale import budget_of, default_epsilon

    n = 10
    D = _plane_points(n, 6)
    for factor in (0.5, 1.0, 2.0):
        budget = budget_of(factor * default_epsilon(D), n, D)
        for L in ([], [2], [2, 7]):
            cand = [p for p in range(n) if p not in L]
            got = swap_floor(D, n, L, cand, budget)
            for p, g in zip(cand, got):
                want = 0.0
                for a in range(n):
                    for b in range(a + 1, n):
                        t = np.arange(n)
                        t[a], t[b] = b, a
                        if a not in L + [p] and b not in L + [p] and _feasible_for(D, t, L + [p], budget):
                            want = max(want, math.sqrt(obj.d2(D, t)))
                assert math.isclose(g, want, rel_tol=1e-9, abs_tol=1e-12), (factor, L, p, g, want)
