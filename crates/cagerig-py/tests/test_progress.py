"""Binding reports its progress to a callable, from the library's one binding path."""

import sys

import cagerig


def test_binding_reports_the_cage_coordinates_it_computes():
    calls = []
    rig = cagerig.Rig.builtin("bar", progress=lambda stage, done, total: calls.append((stage, done, total)))
    n = rig.rest_mesh.shape[0]
    assert calls, "no progress was reported"
    assert {stage for stage, _, _ in calls} == {"cage coordinates"}
    assert {total for _, _, total in calls} == {n}
    assert max(done for _, done, _ in calls) == n


def test_an_exception_in_the_callback_is_reported_and_the_rig_still_binds(monkeypatch):
    seen = []
    monkeypatch.setattr(sys, "unraisablehook", seen.append)

    def broken(stage, done, total):
        raise RuntimeError("the progress bar broke")

    rig = cagerig.Rig.builtin("bar", progress=broken)
    assert rig.rest_mesh.shape[0] > 0
    assert seen and "the progress bar broke" in str(seen[0].exc_value)
