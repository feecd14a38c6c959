"""Checks the 2D and 3D mortar tests share: the two bodies' wear balance under finite sliding, a state's
checkpoint read back, and a half model's symmetry-plane rows and twin nodes in the full model."""

import numpy as np
import pytest

#: A finite-sliding pairing's arrays a checkpoint must give back bit for bit (H checked apart).
PAIRING_ARRAYS = ("master_nodes", "master_weights", "tributary", "gap0", "master_sizes", "paired_separation")


def assert_wear_balance(problem, state, alpha: float) -> tuple[float, float]:
    """Finite sliding with ``EnergyWear(alpha_slave=alpha, alpha_master=1.5 alpha)``: the slave's worn measure
    (depth over its nodes' own measures) is the master's over 1.5 and the two are 2.5 alpha times the dissipated
    energy, to 1e-10 (rounding of sums over a few contacts and increments). Returns (slave, master)."""
    pairing = problem.contact_set_of(state)
    worn = problem.body_wear(state)
    slave = float(worn["slave"] @ pairing.slave_areas)
    master = float(state.master_wear @ problem.operators.surface_compliance.master_areas)
    assert slave == pytest.approx(master / 1.5, rel=1e-10)
    assert slave + master == pytest.approx(2.5 * alpha * state.dissipated_energy, rel=1e-10)
    return slave, master


def assert_checkpoint_round_trip(problem, state, path: str, finite: bool):
    """``state`` saved to ``path`` and loaded back is the same state (and with finite sliding the same pairing, H
    included, and master wear), bit for bit. Returns the state read back."""
    problem.save_state(state, path)
    back, _ = problem.load_state(path)
    for name in ("forces", "positions", "slip", "wear_gap", "obstacle"):
        assert np.array_equal(getattr(back, name), getattr(state, name))
    if finite:
        for name in PAIRING_ARRAYS:
            assert np.array_equal(getattr(back.pairing, name), getattr(state.pairing, name)), name
        assert (back.pairing.H != state.pairing.H).nnz == 0
        assert np.array_equal(back.master_wear, state.master_wear)
    return back


def assert_plane_rows_held(problem) -> None:
    """A 3D half model (a roller on y = 0): the contacts on the plane have their t2 rows held, and only they."""
    on_plane = np.flatnonzero(np.abs(problem.contact.contact_set.coords[:, 1]) <= 1e-12)
    assert on_plane.size > 0 and problem.contact.held_rows.tolist() == (3 * on_plane + 2).tolist()


def assert_half_is_full(half: dict, full: dict, rel: float = 1e-6) -> None:
    """The half model's contact fields (``contact_fields``) equal their twin nodes' in the full model, pressure and
    shear, to ``rel`` of the largest."""
    twin = {tuple(np.round(x, 12)): i for i, x in enumerate(full["coordinates"])}
    index = np.array([twin[tuple(np.round(x, 12))] for x in half["coordinates"]])
    for key in ("pressure", "shear"):
        scale = np.abs(full[key]).max()
        assert np.abs(half[key] - full[key][index]).max() <= rel * scale, key
