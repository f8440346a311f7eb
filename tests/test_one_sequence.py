"""Both front doors run the one sequence of :mod:`gaitopt.orbit.solve` (issue 19 item 2):
:func:`gaitopt.find_limit_cycle` and :func:`gaitopt.optimize_gait` refine their orbit through
``refine`` and certify it through ``certificate``, and a refusal by that certificate is a
``not_a_gait`` of the one STATUS table at either door.  (That the certificate refuses an optimum
whose trailing foot does not lift off, the ``at_start`` rate rule, through the optimiser's door:
tests/test_certificate.py::test_an_optimum_whose_trailing_foot_does_not_lift_off_is_refused.)

Spies wrap the real stages (they forward every call and return its result), so the gaits below
are the real ones; the compass gait's passive gait (default slope) and its least-effort gait on
level ground (0.3 m in 0.8 s, the README's statement)."""

from __future__ import annotations

import gaitopt
from gaitopt.optimize.transcription import CollocationTranscription
from gaitopt.orbit import solve as sequence
from gaitopt.result import STATUS
from gaitopt.shooting.transcription import ShootingTranscription

STATEMENT = dict(period=0.8, step_length=0.3)


def _both_doors():
    cycle = gaitopt.find_limit_cycle(gaitopt.model("compass_gait"))
    gait = gaitopt.optimize_gait(gaitopt.model("compass_gait", slope=0.0), "effort", **STATEMENT)
    return cycle, gait


def test_both_front_doors_refine_and_certify_through_the_one_sequence(monkeypatch):
    calls: list[tuple[str, object, object]] = []
    refine, certificate = sequence.refine, sequence.certificate

    def spy_refine(t, *args, **kwargs):
        out = refine(t, *args, **kwargs)
        calls.append(("refine", t, out))
        return out

    def spy_certificate(t, w, **kwargs):
        out = certificate(t, w, **kwargs)
        calls.append(("certificate", t, out))
        return out

    monkeypatch.setattr(sequence, "refine", spy_refine)
    monkeypatch.setattr(sequence, "certificate", spy_certificate)
    cycle, gait = _both_doors()
    assert cycle.success and gait.success, (cycle.message, gait.message)
    assert cycle.status == gait.status == "success" and cycle.status in STATUS

    def stage(name, kind):
        return [out for n, t, out in calls if n == name and isinstance(t, kind)]

    # The shooting door: one refine (its discretisation error is the one reported, the same
    # number passed on: exact) and one certificate that passed.
    (shooting,) = stage("refine", ShootingTranscription)
    assert shooting.status == "converged"
    assert cycle.discretisation_error == shooting.error
    assert stage("certificate", ShootingTranscription) == [None]
    # The optimiser's door: its mesh refinement is the same stage (a posteriori: the change of
    # cost and orbit), its certificate the same function on the collocation polynomials.
    (optimum,) = stage("refine", CollocationTranscription)
    assert optimum.status == "converged" and optimum.refinements >= 1
    assert gait.discretisation_error == optimum.error
    assert gait.discretisation["cost_error"] == optimum.error_parts["cost"]
    assert stage("certificate", CollocationTranscription) == [None]


def test_a_defect_of_the_one_certificate_refuses_at_both_doors(monkeypatch):
    # The certificate stage reads the one certify_orbit; a defect it reports (injected here on
    # top of the real checks, which pass) is a not_a_gait at either door, in its words.
    real = sequence.certify_orbit

    def refusing(*args, **kwargs):
        assert real(*args, **kwargs) is None  # the real certificate passes these gaits
        return "no gait: injected defect"

    monkeypatch.setattr(sequence, "certify_orbit", refusing)
    cycle, gait = _both_doors()
    for result in (cycle, gait):
        assert not result.success
        assert result.status == "not_a_gait"
        assert "injected defect" in result.message
