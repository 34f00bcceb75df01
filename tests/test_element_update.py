"""The model update of a lumped nominal (gap.connections.update): its
masses and springs fitted to a measured frequency response."""
import numpy as np
import pytest
from scipy.linalg import eigh

from sklearn_pnlss.gap.connections.recalibrate import ModalCorrection
from sklearn_pnlss.gap.connections.update import (ElementCorrection, ElementUpdate, _paired, linear_corrections,
                                                  updated_elements)
from sklearn_pnlss.physics import Structure

POINTS = ["base", "middle", "tip"]
MASSES = np.array([3.0, 2.0, 1.0])
SPRINGS = np.array([1e5, 5e4, 5e4])  # base-ground, middle-base, tip-middle


def chain(masses, springs, damping=1.0):
    k0, k1, k2 = springs
    K = np.array([[k0 + k1, -k1, 0.0], [-k1, k1 + k2, -k2], [0.0, -k2, k2]])
    M = np.diag(MASSES)  # the damping of the true structure, times a factor
    C = damping * (1e-4 * np.array([[1.5e5, -5e4, 0.0], [-5e4, 1e5, -5e4], [0.0, -5e4, 5e4]]) + 0.5 * M)
    return Structure(np.diag(masses), C, K, points=POINTS)


def damping_ratios(structure):
    w2, shapes = eigh(structure.stiffness, structure.mass)
    return np.diag(shapes.T @ structure.damping @ shapes) / (2 * np.sqrt(w2))


def measured(structure, rng, noise=0.01):
    freqs = np.arange(20, 1640, 2) * 200.0 / 4096
    sensors = [(p, "acceleration") for p in POINTS]
    H = structure.frequency_response(freqs, inputs=["base"], sensors=sensors)
    return freqs, H * (1 + noise * rng.standard_normal(H.shape)), sensors


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_chain_10_to_30_percent_off_is_updated_to_its_masses_and_springs(seed):
    rng = np.random.default_rng(seed)
    truth = chain(MASSES, SPRINGS)
    freqs, H, sensors = measured(truth, rng)
    off = lambda a: a * (1 + rng.choice([-1, 1], a.size) * rng.uniform(0.1, 0.3, a.size))  # noqa: E731
    nominal = chain(off(MASSES), off(SPRINGS), damping=1.5)
    weights = 1.0 / np.sqrt(np.mean(np.abs(H) ** 2, axis=(0, 2)))
    updated, factors = updated_elements(nominal, freqs, H, weights, fs=200.0, inputs=["base"], sensors=sensors)

    def misfit(s):
        G = s.frequency_response(freqs, inputs=["base"], sensors=sensors)
        return np.sqrt(np.mean(np.abs(G - H) ** 2) / np.mean(np.abs(H) ** 2))

    assert misfit(nominal) > 0.3
    assert misfit(updated) < 0.012  # the 1 % noise
    # three sensors on three masses: every element is seen, and recovered
    np.testing.assert_allclose(np.diag(updated.mass), MASSES, rtol=0.03)
    np.testing.assert_allclose(updated.stiffness, truth.stiffness, rtol=0.03, atol=0.03 * SPRINGS.max())
    np.testing.assert_allclose(damping_ratios(updated), damping_ratios(truth), rtol=0.05)
    assert set(factors) == {"mass base", "mass middle", "mass tip", "spring base - middle", "spring middle - tip",
                            "spring base - ground", *(f"damping ratio of mode {i}" for i in (1, 2, 3))}


def test_an_exact_nominal_is_left_nearly_as_it_is():
    rng = np.random.default_rng(3)
    truth = chain(MASSES, SPRINGS)
    freqs, H, sensors = measured(truth, rng)
    weights = 1.0 / np.sqrt(np.mean(np.abs(H) ** 2, axis=(0, 2)))
    _, factors = updated_elements(truth, freqs, H, weights, fs=200.0, inputs=["base"], sensors=sensors)
    assert max(abs(np.log(f)) for f in factors.values()) < 0.02


def test_elements_are_read_off_a_lumped_structure_only():
    elements = ElementUpdate.of(chain(MASSES, SPRINGS))
    assert elements.n_params == 9
    same = elements.applied(np.zeros(9))
    np.testing.assert_allclose(same.stiffness, chain(MASSES, SPRINGS).stiffness)
    np.testing.assert_allclose(same.damping, chain(MASSES, SPRINGS).damping, atol=1e-9)  # proportional
    modal = Structure.from_modes([5.0, 12.0], [0.02, 0.01], [[0.5, 0.4], [0.6, -0.3]], points=["a", "b"])
    assert ElementUpdate.of(modal) is None


def test_modes_are_paired_in_order_past_a_spurious_or_missing_one():
    measured_modes = np.array([7.1, 21.8, 22.3, 30.7, 46.6])  # one spurious pole at 22.3 Hz
    model = np.array([6.3, 22.8, 31.4, 42.8])
    got_measured, got_model = _paired(measured_modes, model)
    assert list(zip(got_measured, got_model)) == [(0, 0), (2, 1), (3, 2), (4, 3)]
    got_model, got_measured = _paired(model, measured_modes)  # either list may be the shorter
    assert list(zip(got_measured, got_model)) == [(0, 0), (2, 1), (3, 2), (4, 3)]


def test_the_element_corrections_are_the_response_s_first_order_change():
    # a 0.01 % change of every element: the columns predict the response's
    # change but for its second order (a 0.1 % change left 8 %: these
    # resonances are 0.5-1 % damped)
    nominal = chain(MASSES, SPRINGS)
    freqs = np.arange(20, 1640, 2) * 200.0 / 4096
    sensors = [(p, "acceleration") for p in POINTS]
    correction = linear_corrections(nominal, freqs, inputs=["base"], sensors=sensors)
    assert isinstance(correction, ElementCorrection) and correction.n_params == 3 + 3 + 3
    theta = 1e-4 * np.random.default_rng(0).choice([-1, 1], correction.n_params)
    U = np.ones((freqs.size, 1))
    change = (correction.applied(theta).frequency_response(freqs, inputs=["base"], sensors=sensors)
              - correction.applied(0 * theta).frequency_response(freqs, inputs=["base"], sensors=sensors))[:, :, 0]
    predicted = correction.columns(U) @ theta
    assert np.linalg.norm(predicted - change) < 0.02 * np.linalg.norm(change)
    # a modal structure has no elements: its in-band modes are corrected
    modal = Structure.from_modes([5.0, 12.0], [0.02, 0.01], [[0.5, 0.4], [0.6, -0.3]], points=["a", "b"])
    assert isinstance(linear_corrections(modal, freqs, inputs=["a"], sensors=[("b", "acceleration")]),
                      ModalCorrection)
