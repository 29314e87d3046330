"""This machine's contacts against contacts another machine computed, within the derived bound.

A results file from a CPU the development machines may lack (AVX-512 with OpenBLAS's
SkylakeX kernel, and the same machine under its Haswell kernel) is read where it is kept
beside the project: ``../shared/kernels/`` from the repository root (or the main checkout's,
from a git worktree), or the folder named by ``IMPACT_HARNESS_KERNEL_DATA``. A user's clone
has no such folder: the test skips, saying so. Nothing of the file is copied here.

Each recorded contact, the library's and the reference form's (tests/scene/
test_geometry_reference.py) under both kernels, must be within the sum of two forward error
bounds of this machine's :func:`harness.scene.geometry.body_contact` (tests/scene/
contact_bounds.py derives it; tests/error_bounds.py holds the formulas): a derived bound, no
count of units in the last place. Where a decision (which pair is closest, which axis
separates most, which points are near, one point or two) is within its band, either outcome
is accepted: the gap is compared still, the normal against each outcome's, the point not.

Two checks need no file: a BLAS form of the contacts (every product through numpy's ``@``,
under whichever kernel tests/other_kernels.py chose) within the same bound, and the bound
itself against the exact contact (rational arithmetic) where the cores are apart.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

from harness.scene import Body, Box, Contact, Disk, Polygon, Rod, geometry
from tests.scene.contact_bounds import contact_bound

FILE_NAME = "avx512-geometry-contacts.json"
#: names a folder holding the file, where the repository's ../shared/kernels/ does not
ENVIRONMENT = "IMPACT_HARNESS_KERNEL_DATA"
RECORDED = ("implementation_skylakex", "implementation_haswell", "reference_skylakex",
            "reference_haswell")
#: A sanity cap on the derived bound itself (of the normal, and of the gap relative to
#: 1 + |gap|), not a tolerance of any comparison: it fails a derivation gone vacuous (inf,
#: NaN, or O(1) where cores nearly touch), under which every comparison would pass. Not
#: derived, and not meant to be tight: how much of the bound the contacts use is checked
#: against exact rational arithmetic (test_the_derived_bound_holds_against_exact_arithmetic)
#: and the bound's size is the derivation's (tests/scene/contact_bounds.py). 1e-6 stays far
#: below what the contacts decide downstream (engine departures are read at 1e-3 and
#: above). Measured on the AVX-512 file's 512 cases: at most 1.1e-11 (case 670), 1e-5 of it.
USEFUL_BOUND = 1e-6


ROOT = Path(__file__).resolve().parents[2]


def data_file(root: Path = ROOT, environment=os.environ) -> Path | None:
    """The other machine's file beside the checkout at ``root``, or ``None`` where it has
    none."""
    folders = [Path(environment[ENVIRONMENT])] if environment.get(ENVIRONMENT) else []
    folders.append(root.parent / "shared" / "kernels")
    try:  # a git worktree: beside the main checkout
        common = subprocess.run(["git", "rev-parse", "--path-format=absolute",
                                 "--git-common-dir"], cwd=root, capture_output=True,
                                text=True, timeout=30, check=True).stdout.strip()
        folders.append(Path(common).parent.parent / "shared" / "kernels")
    except (OSError, subprocess.SubprocessError):
        pass
    for folder in folders:
        if (folder / FILE_NAME).is_file():
            return folder / FILE_NAME
    return None


def shape_of(document: dict):
    number = float.fromhex
    kind = document["kind"]
    if kind == "disk":
        return Disk(number(document["radius"]))
    if kind == "rod":
        return Rod(number(document["length"]), number(document["radius"]))
    if kind == "box":
        return Box(number(document["width"]), number(document["height"]))
    if kind == "polygon":
        return Polygon(tuple((number(x), number(y)) for x, y in document["points"]))
    raise ValueError(f"{FILE_NAME}: shape kind {kind!r}; allowed: disk, rod, box, polygon")


def body_of(name: str, document: dict) -> Body:
    return Body(name, shape_of(document["shape"]), 1.0,
                tuple(float.fromhex(v) for v in document["position"]),
                float.fromhex(document["angle"]))


def vector(values) -> np.ndarray:
    return np.array([float.fromhex(v) for v in values])


@pytest.fixture(scope="module")
def cases():
    path = data_file()
    if path is None:
        pytest.skip(f"no {FILE_NAME} beside this checkout (../shared/kernels/ or "
                    f"${ENVIRONMENT}): the other machine's contacts are not here")
    return json.loads(path.read_text())["cases"]


def assert_within_bound(there, here, bound, what) -> bool:
    """Contact ``there`` (another machine's or form's) is ``here`` (this machine's library)
    within twice ``bound`` (each of the two within it of the exact contact); where a decision
    is within its band (``bound.undecided``), the gap still and the normal against each
    outcome's, the point and its count not. Whether the case was decided."""
    gap = abs(there.gap - here.gap)
    assert gap <= 2 * bound.gap, f"gap {gap:.3g} > {2 * bound.gap:.3g} in {what}: {bound}"
    normal = min(np.abs(np.asarray(there.normal) - n).max() for n in bound.normals)
    assert normal <= 2 * bound.normal, f"normal {normal:.3g} in {what}: {bound}"
    if bound.undecided:
        return False
    assert there.point_count == here.point_count, f"point count in {what}: {bound}"
    point = np.abs(np.asarray(there.point) - here.point).max()
    assert point <= 2 * bound.point, f"point {point:.3g} in {what}: {bound}"
    return True


def assert_checks_have_teeth(kinds: set, decided: int, undecided: int) -> None:
    """Bounds that said nothing, or decisions left open everywhere, would pass anything: the
    decided cases outnumber the others and hold cores apart and overlapping, one point and
    two."""
    assert decided > undecided, (decided, undecided)
    assert {apart for apart, _ in kinds} == {True, False}, kinds
    assert {count for _, count in kinds} == {1, 2}, kinds


def contact_of(document: dict):
    return Contact(point=vector(document["point"]), normal=vector(document["normal"]),
                   gap=float.fromhex(document["gap"]), point_count=document["point_count"])


@pytest.mark.kernel_sensitive
def test_another_machines_contacts_are_this_machines_within_the_derived_bound(cases):
    decided = undecided = 0
    kinds = set()
    for case in cases:
        a, b = body_of("a", case["a"]), body_of("b", case["b"])
        tolerance = float.fromhex(case["tolerance"])
        here = geometry.body_contact(a, b, tolerance)
        bound = contact_bound(a, b, tolerance)
        assert max(bound.normal, bound.gap / (1.0 + abs(here.gap))) < USEFUL_BOUND, (
            case["case"], bound)
        outcomes = {assert_within_bound(contact_of(case[name]), here, bound,
                                        f"case {case['case']}, {name}") for name in RECORDED}
        if outcomes == {True}:
            kinds.add((here.gap > 0, here.point_count))
        decided += outcomes == {True}
        undecided += outcomes != {True}
    assert_checks_have_teeth(kinds, decided, undecided)


def test_the_file_is_found_beside_the_checkout_or_where_named_and_else_skipped(tmp_path):
    clone = tmp_path / "clone"  # not a git checkout, nothing beside it: the test skips
    clone.mkdir()
    assert data_file(clone, {}) is None
    assert data_file(clone, {ENVIRONMENT: str(tmp_path / "absent")}) is None
    named = tmp_path / "named"
    named.mkdir()
    (named / FILE_NAME).write_text("{}")
    assert data_file(clone, {ENVIRONMENT: str(named)}) == named / FILE_NAME
    beside = tmp_path / "shared" / "kernels"
    beside.mkdir(parents=True)
    (beside / FILE_NAME).write_text("{}")
    assert data_file(clone, {}) == beside / FILE_NAME


def blas_world_core(body):
    """The world core as the library once formed it: one BLAS product with the rotation."""
    local, radius = geometry.local_core(body.shape)
    return local @ geometry.rotation(body.angle).T + np.asarray(body.position), radius


@pytest.mark.kernel_sensitive
def test_a_blas_form_of_the_contacts_is_within_the_derived_bound(monkeypatch):
    # The reference form with every product through numpy's ``@`` (BLAS: this run's kernel,
    # FMA or not, AVX-512 under tests/other_kernels.py where the CPU has it), the form whose
    # rounding once failed an 8-ulp bound, against the library's elementwise contacts: a
    # derived bound holds for any rounding, on any machine, with or without the file above.
    # (Under some kernels the two forms round alike in most cases: nothing to bound there.)
    from tests.scene import test_geometry_reference as reference

    monkeypatch.setattr(reference, "_dot", lambda a, b: float(a @ b))
    monkeypatch.setattr(reference, "_times", lambda core, direction: core @ direction)
    monkeypatch.setattr(reference, "reference_world_core", blas_world_core)
    rng = np.random.default_rng(20261122)
    decided = undecided = 0
    kinds = set()
    for _ in range(750):
        a = Body("a", reference.random_shape(rng), 1.0, (0.0, 0.0), reference.random_angle(rng))
        position = rng.uniform(-1.0, 1.0, 2) * float(rng.choice([0.0, 0.1, 0.5, 1.0]))
        b = Body("b", reference.random_shape(rng), 1.0, (float(position[0]), float(position[1])),
                 reference.random_angle(rng))
        for tolerance in reference.TOLERANCES:
            here = geometry.body_contact(a, b, tolerance)
            blas = reference.reference_body_contact(a, b, tolerance)
            if assert_within_bound(blas, here, contact_bound(a, b, tolerance), (a, b, tolerance)):
                kinds.add((here.gap > 0, here.point_count))
                decided += 1
            else:
                undecided += 1
    assert_checks_have_teeth(kinds, decided, undecided)


def exact_apart_contact(body_a: Body, body_b: Body):
    """The contact of two bodies whose cores are apart, in exact arithmetic (rationals; one
    square root to 50 digits): ``(gap, normal, point)`` as Decimals, from the library's own
    ``cos`` and ``sin`` taken as exact (their libm error is step 1's other part)."""
    from decimal import Decimal, localcontext
    from fractions import Fraction

    def core(body):
        local, radius = geometry.local_core(body.shape)
        c, s = Fraction(math.cos(body.angle)), Fraction(math.sin(body.angle))
        px, py = (Fraction(v) for v in body.position)
        return [(Fraction(x) * c - Fraction(y) * s + px, Fraction(x) * s + Fraction(y) * c + py)
                for x, y in local.tolist()], Fraction(radius)

    def edges(points):
        return [(points[0], points[-1])] if len(points) <= 2 else list(
            zip(points, points[1:] + points[:1]))

    def foot(x, start, end):
        d = (end[0] - start[0], end[1] - start[1])
        length2 = d[0] * d[0] + d[1] * d[1]
        if length2 == 0:
            return start
        t = ((x[0] - start[0]) * d[0] + (x[1] - start[1]) * d[1]) / length2
        t = min(Fraction(1), max(Fraction(0), t))
        return (start[0] + t * d[0], start[1] + t * d[1])

    (core_a, radius_a), (core_b, radius_b) = core(body_a), core(body_b)
    pairs = [(x, foot(x, *edge)) for x in core_a for edge in edges(core_b)]
    pairs += [(foot(x, *edge), x) for x in core_b for edge in edges(core_a)]
    on_a, on_b = min(pairs, key=lambda pair: (pair[1][0] - pair[0][0]) ** 2
                     + (pair[1][1] - pair[0][1]) ** 2)
    with localcontext() as context:
        context.prec = 50

        def decimal(value):
            return Decimal(value.numerator) / Decimal(value.denominator)

        vx, vy = decimal(on_b[0] - on_a[0]), decimal(on_b[1] - on_a[1])
        distance = (vx * vx + vy * vy).sqrt()
        normal = (vx / distance, vy / distance)
        ra, rb = decimal(radius_a), decimal(radius_b)
        point = tuple((decimal(on_a[i]) + ra * normal[i] + decimal(on_b[i]) - rb * normal[i]) / 2
                      for i in range(2))
        return distance - ra - rb, normal, point


def test_the_derived_bound_holds_against_exact_arithmetic():
    # The bound is a claim about the distance from the exact contact: checked against exact
    # rational arithmetic where the cores are apart and one point touches (steps 1 and 2).
    from decimal import Decimal

    from tests.scene import test_geometry_reference as reference

    rng = np.random.default_rng(2035)
    checked = 0
    for _ in range(400):
        a = Body("a", reference.random_shape(rng), 1.0, (0.0, 0.0), reference.random_angle(rng))
        position = rng.uniform(-1.0, 1.0, 2) * float(rng.choice([0.1, 0.5, 1.0]))
        b = Body("b", reference.random_shape(rng), 1.0, (float(position[0]), float(position[1])),
                 reference.random_angle(rng))
        here = geometry.body_contact(a, b)
        bound = contact_bound(a, b, geometry.DEFAULT_TOLERANCE)
        radii = geometry.local_core(a.shape)[1] + geometry.local_core(b.shape)[1]
        if here.gap + radii <= 0.0 or here.point_count != 1 or bound.undecided:
            continue
        gap, normal, point = exact_apart_contact(a, b)
        what = (a, b, bound)
        assert abs(Decimal(here.gap) - gap) <= Decimal(bound.gap), what
        assert max(abs(Decimal(float(v)) - n) for v, n in zip(here.normal, normal)) <= Decimal(
            bound.normal), what
        assert max(abs(Decimal(float(v)) - p) for v, p in zip(here.point, point)) <= Decimal(
            bound.point), what
        checked += 1
    assert checked > 100, checked
