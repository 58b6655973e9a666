"""The conditioning of ``A Aᵀ`` (its eigenvalues, exactly or by Lanczos), against design
parameters, and the CASSI-VSI arm study (thesis Section 3.3.1)."""

from __future__ import annotations

import inspect
import numbers

import numpy as np

from ..validate import imager
from .sweeping import seed_list

__all__ = ["conditioning", "conditioning_design", "vsi_arms", "SHAPE_PARAMETERS"]

#: Design parameters that are an axis of the cube: ``(system, name) → axis``.
SHAPE_PARAMETERS = {
    ("cassdi_dfa", "n_depths"): 3,
    ("cs2li", "n_patterns"): 3,
    ("mu_cosdi", "n_patterns"): 3,
}
#: The thesis' splitting ratios αT = 0, 0.1, …, 1.
ALPHAS = tuple(round(0.1 * i, 1) for i in range(11))
#: Default cube shapes of the sweep (32 × 32 × 8, plus the extra axis of 4-D imagers).
DEFAULT_SHAPES = {"cassdi_dfa": (32, 32, 8, 3), "cs2li": (32, 32, 8, 4), "mu_cosdi": (32, 32, 8, 4)}


def _parameters(cls, name):
    """Keyword names a design sweep may set on ``cls``: its ``example`` and constructor's."""
    keys = set()
    for fn in (cls.example, cls.__init__):
        keys |= {
            p.name
            for p in inspect.signature(fn).parameters.values()
            if p.kind is inspect.Parameter.KEYWORD_ONLY
        }
    keys |= {p for (s, p) in SHAPE_PARAMETERS if s == name}
    return sorted(keys - {"rng", "wavelengths", "code", "codes", "psfs"})


def conditioning_design(
    system, parameter, values, *, cube_shape=None, seeds=(0,), exact_below=4096, **fixed
) -> list[dict]:  # fmt: skip
    """How the conditioning of ``A Aᵀ`` moves with one design parameter of an imager.

    Builds ``REGISTRY[system].example(cube_shape, rng=seed, parameter=value,
    **fixed)`` for every value and seed and runs
    :func:`~tensor_cosdi.studies.conditioning` on it.  Parameters that are an
    axis of the cube (:data:`SHAPE_PARAMETERS`: DFA depth planes
    ``n_depths``, CS2LI / Mu-CoSDI ``n_patterns``) replace that axis of
    ``cube_shape`` (default 32 × 32 × 8, with 3 depth planes or 4 patterns
    for the 4-D imagers).  Examples: CASSI-VSI ``alpha_t`` and ``beta``, SD-/DD-CASSI
    ``shots`` (multishot K) and ``transmittance``, CS2LI ``n_filters``,
    CASSDI-DFA ``n_depths``.  (CS2LI's fringe frequencies are not a
    parameter of ``A``: the patterns are part of the cube, so ``A Aᵀ`` does
    not depend on them.)

    Returns
    -------
    list of dict
        One record per (value, seed): ``system``, the parameter's name with
        its value, ``seed`` and every key of
        :func:`~tensor_cosdi.studies.conditioning` (``cond_nonzero``,
        ``lambda_min_nonzero``, ``lambda_max``, ``zero``, Gershgorin bounds,
        ``structure``, ``method``).

    Examples
    --------
    >>> from tensor_cosdi import studies
    >>> recs = studies.conditioning_design("sd_cassi", "shots", [1, 2], cube_shape=(8, 8, 4))
    >>> [(r["shots"], r["structure"]) for r in recs]
    [(1, 'diagonal'), (2, 'pixel_blocks')]
    """
    from .problems import SYSTEMS

    cls = SYSTEMS[system]  # an unknown name lists the registered ones
    allowed = _parameters(cls, system)
    if parameter not in allowed:
        raise ValueError(f"{parameter!r} is not a design parameter of {system!r}; it has {allowed}")
    default = DEFAULT_SHAPES.get(system, (32, 32, 8))
    cube_shape = default if cube_shape is None else tuple(cube_shape)
    if len(cube_shape) != len(default):
        raise ValueError(
            f"cube_shape of {system!r} has {len(default)} axes (e.g. {default}), got {cube_shape}"
        )
    if isinstance(values, (str, bytes)) or not hasattr(values, "__iter__"):
        raise ValueError(f"values must be a sequence of the parameter's values, got {values!r}")
    values = list(values)
    if not values:
        raise ValueError("values is empty: give the parameter values to sweep")
    seeds = seed_list(seeds)
    records = []
    for value in values:
        for seed in seeds:
            shape = list(cube_shape)
            kwargs = dict(fixed)
            axis = SHAPE_PARAMETERS.get((system, parameter))
            if axis is not None:
                if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 1:
                    raise ValueError(f"{parameter} must be a positive integer, got {value!r}")
                shape[axis] = int(value)
            else:
                kwargs[parameter] = value
            sys_ = cls.example(tuple(shape), rng=seed, **kwargs)
            c = conditioning(sys_, exact_below=exact_below)
            records.append({"system": system, parameter: value, "seed": seed, **c})
    return records


def _row_blocks_hdt(system):
    """Per-detector-row blocks of ``H Dᵀ`` (``Nx`` matrices ``(Ny + S) × Ny``) of CASSI-VSI.

    ``Dᵀ`` (the adjoint of :attr:`~tensor_cosdi.systems.System.decimation`)
    spreads a panchromatic image over the bands; CASSI-VSI's rows do not mix,
    so probing every column ``j`` of all rows at once gives column ``j`` of
    every row's block."""
    nx, ny, _ = system.cube_shape
    spread = system.decimation.adjoint
    blocks = np.zeros((nx, system.measurement_shape[1], ny))
    for j in range(ny):
        z = np.zeros((nx, ny))
        z[:, j] = 1.0
        blocks[:, :, j] = np.asarray(system.forward(spread(z)))
    return blocks


def vsi_arms(
    scenes=("cave.face",), alphas=ALPHAS, *, snr_db=20.0,
    shape=(64, 64), n_bands=12, seeds=(0,), beta=0,
) -> list[dict]:  # fmt: skip
    """The CASSI-VSI beam-splitter design study of the thesis (Section 3.3.1, Figure 19-20).

    Per splitting ratio ``αT``:

    * ``cond_H`` — κ of ``H Hᵀ`` (the sensing matrix of the cube,
      :func:`~tensor_cosdi.studies.conditioning`) and ``cond_HDt`` — κ of
      ``(H Dᵀ)ᵀ(H Dᵀ)``, the sensing of the panchromatic image ``z`` (``Dᵀ``
      copies ``z`` into every band), exact per detector row; both on the
      matrix's range (a blocked code pixel leaves a zero column of
      ``H Dᵀ`` and detector pixels no light reaches leave zero rows of
      ``H``);
    * ``snr_t`` / ``snr_r`` — the SNR of each arm's share of the
      measurement, ``10 log₁₀(‖g_arm‖² / ‖n‖²)`` with ``n`` the white
      Gaussian noise that puts the whole measurement at ``snr_db``, and
      ``snr_mean`` their mean (the thesis adds noise "coloured by the total
      intensity"; the library's white noise is used here);
    * ``range_error`` — the dynamic-range mismatch of the two arms,
      the mean of ``|gT/gR − gR/gT|`` over detector pixels both arms light
      (the thesis sums it; a mean does not grow with the image).

    The thesis: ``H`` is best conditioned at ``αT = 1`` and ``H Dᵀ`` at
    ``αT = 0``, crossing near 0.75; the arm SNRs cross and their mean peaks
    near 0.6; the dynamic range is balanced near 0.7.  Its study averages
    1000 codes and 50 scenes at 64 × 64 × 12.

    Returns
    -------
    list of dict
        One record per (scene, αT, seed) with the keys above, plus
        ``scene``, ``alpha_t``, ``seed``.

    Examples
    --------
    >>> from tensor_cosdi import studies
    >>> recs = studies.vsi_arms(("colorchecker",), (0.3, 0.7), shape=(8, 8), n_bands=4)
    >>> recs[0]["snr_t"] < recs[1]["snr_t"] and recs[0]["snr_r"] > recs[1]["snr_r"]
    True
    """
    from .. import scenes as sc
    from ..codes import random_binary
    from ..noise import add_noise
    from ..systems import CASSIVSI, wavelengths_for

    alphas = [float(a) for a in alphas]
    bad = [a for a in alphas if not 0.0 <= a <= 1.0]
    if bad or not alphas:
        raise ValueError(f"alphas must be fractions in [0, 1], got {bad or alphas}")
    wl = wavelengths_for(None, n_bands)
    seeds = seed_list(seeds)
    records = []
    for scene in scenes:
        cube = np.asarray(sc.scene_cube(scene, tuple(shape), wl))
        for seed in seeds:
            code = random_binary(tuple(shape), transmittance=0.5, rng=seed)
            for a in alphas:
                vsi = CASSIVSI(code, n_bands=n_bands, alpha_t=a, beta=beta, wavelengths=wl)
                gt = a * np.asarray(vsi.arms[0].forward(cube))
                gr = (1.0 - a) * np.asarray(vsi.arms[1].forward(cube))
                g = gt + gr
                noise = np.asarray(add_noise(g, snr_db, rng=seed)) - g
                en = float((noise**2).sum())

                def arm_snr(x, en=en):
                    e = float((x**2).sum())
                    return float(10 * np.log10(e / en)) if e > 0 else -np.inf

                lit = (gt > 0) & (gr > 0)
                ratio = (
                    float(np.abs(gt[lit] / gr[lit] - gr[lit] / gt[lit]).mean())
                    if lit.any() else float("nan")
                )  # fmt: skip
                s = np.linalg.svd(_row_blocks_hdt(vsi), compute_uv=False).ravel()
                s = s[s > 1e-8 * s.max()]  # blocked code pixels: z there is invisible
                h = conditioning(vsi)
                records.append({
                    "scene": scene, "alpha_t": a, "seed": seed,
                    "cond_H": h["cond_nonzero"], "cond_HDt": float((s.max() / s.min()) ** 2),
                    "snr_t": arm_snr(gt), "snr_r": arm_snr(gr),
                    "snr_mean": (arm_snr(gt) + arm_snr(gr)) / 2, "range_error": ratio,
                })  # fmt: skip
    return records


def conditioning(system, *, exact_below: int = 4096, tol: float = 1e-8) -> dict:
    """How well posed the system's Woodbury inner matrix ``A Aᵀ`` is (SPEC §4).

    The system's :meth:`~tensor_cosdi.operators.TensorOperator.conditioning`:
    extreme eigenvalues, condition numbers with and without the zero
    eigenvalues (measurement entries no voxel reaches), Gershgorin bounds,
    the structure of ``A Aᵀ`` and the method used (exact from the structure,
    dense below ``exact_below`` measurements, else Lanczos).
    """
    imager(system)
    return system.operator.conditioning(exact_below=exact_below, tol=tol)
