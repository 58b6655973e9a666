"""Coded-aperture generators: binary codes, complementary colour codes, ``#f``/``κ`` designs.

Every generator is seeded (``rng`` is a seed or a NumPy ``Generator``) and
returns a float64 NumPy array of transmittances in ``[0, 1]``, ready to pass to
the constructors in :mod:`tensor_cosdi.systems`.

============================================  =========================================
generator                                     used by
============================================  =========================================
:func:`random_binary`                          SD/DD-CASSI, CASSI-VSI, Mu-CoSDI, CS2LI
:func:`depth_codes`                            CASSDI-DFA (one code per focal step)
:func:`complementary_colour_codes`             C3SLFI (``Σ_k T[..., k] = 1``, Lemma 1)
:func:`colour_coded_aperture`                  CS2LI (``#f`` filters, transmittance ``κ``)
:func:`is_complementary`                       checks Lemma 1's condition
============================================  =========================================
"""

from __future__ import annotations

import numbers

import numpy as np

from . import _backend as B
from .validate import axis_index, number, real_array

__all__ = [
    "random_binary",
    "depth_codes",
    "complementary_colour_codes",
    "colour_coded_aperture",
    "filter_passbands",
    "is_complementary",
]


def _shape(shape, what="shape") -> tuple[int, ...]:
    if isinstance(shape, numbers.Integral):
        shape = (shape,)
    try:
        out = tuple(int(n) for n in shape)
    except TypeError:
        raise ValueError(f"{what} must be a tuple of positive integers, got {shape!r}") from None
    if any(isinstance(n, bool) or n < 1 for n in shape) or any(
        not isinstance(n, numbers.Integral) for n in shape
    ):
        raise ValueError(f"{what} must be a tuple of positive integers, got {shape!r}")
    if not out:  # (an empty tuple, or an array of no rows, iterated)
        raise ValueError(f"{what} must have at least one axis, got {shape!r}")
    return out


def _count(value, what, minimum=1) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < minimum:
        raise ValueError(f"{what} must be an integer ≥ {minimum}, got {value!r}")
    return int(value)


def _fraction(value, what) -> float:
    return number(what, value, low=0, low_open=True, high=1)


def random_binary(shape, *, transmittance: float = 0.5, rng=None) -> np.ndarray:
    """Seeded random binary code: each entry is 1 with probability ``transmittance``.

    Parameters
    ----------
    shape : tuple of int
        E.g. ``(Nx, Ny)`` for a coded aperture, ``(Nx, Ny, K)`` for ``K`` shots.
    transmittance : float in (0, 1]
        Probability that an element is open (SPEC §3: default 50 %).
    rng : int or numpy.random.Generator, optional

    Examples
    --------
    >>> c = random_binary((64, 64), transmittance=0.25, rng=0)
    >>> sorted(set(c.ravel().tolist())), round(float(c.mean()), 2)
    ([0.0, 1.0], 0.25)
    """
    shape = _shape(shape)
    p = _fraction(transmittance, "transmittance")
    return (B.default_rng(rng).random(shape) < p).astype(np.float64)


def depth_codes(shape, n_depths: int, *, transmittance: float = 0.5, rng=None) -> np.ndarray:
    """One random binary code per focal step of CASSDI-DFA: shape ``shape + (n_depths,)``.

    Examples
    --------
    >>> depth_codes((8, 9), 3, rng=1).shape
    (8, 9, 3)
    """
    shape = _shape(shape)
    n_depths = _count(n_depths, "n_depths")
    return random_binary(shape + (n_depths,), transmittance=transmittance, rng=rng)


def filter_passbands(n_bands: int, n_filters: int) -> np.ndarray:
    """Split ``n_bands`` bands into ``n_filters`` contiguous pass-bands of near-equal width.

    Returns a ``(n_filters, n_bands)`` 0/1 array; row ``f`` is the transmission
    of filter ``f`` (filter 0 the shortest wavelengths, like the low-pass /
    high-pass pair of the C3SLFI prototype, thesis Fig. 50).  Every band is
    passed by exactly one filter.

    Examples
    --------
    >>> filter_passbands(5, 2).astype(int).tolist()
    [[1, 1, 1, 0, 0], [0, 0, 0, 1, 1]]
    """
    n_bands = _count(n_bands, "n_bands")
    n_filters = _count(n_filters, "n_filters")
    if n_filters > n_bands:
        raise ValueError(f"n_filters={n_filters} cannot exceed n_bands={n_bands}")
    which = np.arange(n_bands) * n_filters // n_bands  # filter of each band
    return (which[None, :] == np.arange(n_filters)[:, None]).astype(np.float64)


def complementary_colour_codes(
    cube_shape, n_snapshots: int, *, band_axis: int = 2, n_filters: int | None = None, rng=None
) -> np.ndarray:
    """Complementary colour-coded apertures for ``K`` snapshots (C3SLFI, SPEC §3.3).

    The bands are split into ``n_filters`` contiguous pass-bands
    (:func:`filter_passbands`).  At every pixel (every index of ``cube_shape``
    except ``band_axis``: spatial position and, for a 5-D light field, view)
    each filter is given to one snapshot, so that every band is open in
    exactly one snapshot and ``Σ_k T[..., l, k] = 1`` (Lemma 1, Eq. 89).
    With ``n_filters = K`` (the default) each snapshot receives one filter per
    pixel, in a random order; with more filters the snapshots receive them in
    balanced random groups.

    Parameters
    ----------
    cube_shape : tuple of int
        Shape of the spectral (light-field) cube, e.g. ``(Ñ1, Ñ2, N3)`` or
        ``(N1, N2, N3, N4, N5)``.
    n_snapshots : int ≥ 2
        ``K``.
    band_axis : int
        Axis of ``cube_shape`` that holds the bands (default 2).
    n_filters : int, optional
        Number of pass-bands, ``K ≤ n_filters ≤ N3`` (default ``K``).

    Returns
    -------
    ndarray of shape ``cube_shape + (K,)``, entries 0/1.

    Examples
    --------
    >>> T = complementary_colour_codes((4, 5, 6), 3, rng=0)
    >>> T.shape, bool((T.sum(-1) == 1).all())
    ((4, 5, 6, 3), True)
    """
    shape = _shape(cube_shape, "cube_shape")
    K = _count(n_snapshots, "n_snapshots", 2)
    band_axis = axis_index("band_axis", band_axis, len(shape))
    n_bands = shape[band_axis]
    n_filters = K if n_filters is None else _count(n_filters, "n_filters")
    if not K <= n_filters <= n_bands:
        raise ValueError(
            f"need n_snapshots ≤ n_filters ≤ n_bands, got K={K}, n_filters={n_filters}, "
            f"n_bands={n_bands}"
        )
    passbands = filter_passbands(n_bands, n_filters)  # (F, Nλ)
    pixels = shape[:band_axis] + shape[band_axis + 1 :]
    n_pix = int(np.prod(pixels))
    g = B.default_rng(rng)
    # balanced assignment: filter f → snapshot (f mod K), then a random permutation per pixel
    base = np.arange(n_filters) % K
    keys = g.random((n_pix, n_filters))
    owner = base[np.argsort(keys, axis=1)]  # (n_pix, F): snapshot of each filter at each pixel
    onehot = owner[:, :, None] == np.arange(K)[None, None, :]  # (n_pix, F, K)
    T = np.einsum("pfk,fl->plk", onehot.astype(np.float64), passbands)  # (n_pix, Nλ, K)
    T = T.reshape(pixels + (n_bands, K))
    return np.moveaxis(T, len(pixels), band_axis)


def colour_coded_aperture(
    shape, n_bands: int, *, n_filters: int = 6, transmittance: float = 0.5, rng=None
) -> np.ndarray:
    """Colour-coded aperture with ``#f`` filters and transmittance ``κ`` (thesis Section 6.3.2).

    Each pixel is open with probability ``κ = transmittance``; an open pixel
    carries one of ``#f = n_filters`` contiguous band-pass filters
    (:func:`filter_passbands`), drawn uniformly.  ``#f = 1`` is a binary coded
    aperture of transmittance ``κ`` (all ones at ``κ = 1``); ``#f = Nλ`` puts
    an ideal narrow filter at every open pixel.  The thesis' best trade-off
    for CS2LI is ``#f = 6, κ = 50 %``.  (The thesis does not spell out how
    ``κ`` enters; this is the reading under which both of its limiting cases
    hold.)

    Parameters
    ----------
    shape : tuple of int
        Spatial shape of the aperture, e.g. ``(Nx, Ny + s_max)`` for CS2LI.
    n_bands : int
    n_filters : int, ``1 ≤ #f ≤ n_bands``
    transmittance : float in (0, 1]

    Returns
    -------
    ndarray of shape ``shape + (n_bands,)``, entries 0/1.

    Examples
    --------
    >>> C = colour_coded_aperture((32, 40), 12, n_filters=6, transmittance=0.5, rng=0)
    >>> C.shape, bool((C.sum(-1) == 2).sum() > 0), bool(C.sum(-1).max() == 2)
    ((32, 40, 12), True, True)
    """
    shape = _shape(shape)
    kappa = _fraction(transmittance, "transmittance")
    passbands = filter_passbands(n_bands, n_filters)
    g = B.default_rng(rng)
    open_ = g.random(shape) < kappa
    which = g.integers(0, passbands.shape[0], size=shape)
    return passbands[which] * open_[..., None]


def is_complementary(codes, *, axis: int = -1, atol: float = 1e-9) -> bool:
    """True when ``codes`` sums to 1 along the snapshot ``axis`` (within ``atol``).

    Examples
    --------
    >>> is_complementary(complementary_colour_codes((3, 3, 4), 2, rng=0))
    True
    >>> is_complementary(np.full((3, 3, 4, 2), 0.4))
    False
    """
    c = real_array("codes", B.to_numpy(codes), finite=False)
    tol = number("atol", atol, low=0)
    s = np.sum(c, axis=axis_index("axis", axis, c.ndim))
    return bool(np.all(np.abs(s - 1.0) <= tol))
