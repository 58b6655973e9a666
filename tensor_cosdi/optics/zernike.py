"""Zernike polynomials in Noll order, unit-RMS on the unit disk (SPEC §8, Noll 1976)."""

from __future__ import annotations

import numbers
from math import factorial

import numpy as np

from ..validate import integer, real_array

__all__ = ["noll_to_nm", "zernike", "zernike_radial", "NAMES"]

#: Common names of the first Noll terms.
NAMES = {
    1: "piston",
    2: "tilt x",
    3: "tilt y",
    4: "defocus",
    5: "oblique astigmatism",
    6: "vertical astigmatism",
    7: "vertical coma",
    8: "horizontal coma",
    9: "vertical trefoil",
    10: "oblique trefoil",
    11: "primary spherical",
}


def noll_to_nm(j: int) -> tuple[int, int]:
    """Radial order ``n`` and signed azimuthal frequency ``m`` of Noll index ``j ≥ 1``.

    ``m > 0`` is a cosine term (even ``j``), ``m < 0`` a sine term (odd ``j``).

    Examples
    --------
    >>> [noll_to_nm(j) for j in (1, 2, 3, 4, 5, 6, 11)]
    [(0, 0), (1, 1), (1, -1), (2, 0), (2, -2), (2, 2), (4, 0)]
    """
    if isinstance(j, bool) or not isinstance(j, numbers.Integral) or j < 1:
        raise ValueError(f"Noll index j must be an integer ≥ 1, got {j!r}")
    j = int(j)
    n = 0
    while j > (n + 1) * (n + 2) // 2:
        n += 1
    k = j - n * (n + 1) // 2 - 1  # position inside row n, 0-based
    m = n % 2 + 2 * ((k + (n + 1) % 2) // 2)
    if m == 0:
        return n, 0
    return n, (m if j % 2 == 0 else -m)


#: Highest radial order ``n`` computed (the alternating sum loses every digit of float64 well
#: before it; optical designs use n ≤ 10).
MAX_ORDER = 60


def zernike_radial(n: int, m: int, rho):
    """The radial polynomial ``R_n^|m|(ρ)``: integers ``n ≥ 0`` and ``|m| ≤ n`` with ``n − |m|``
    even (the pairs :func:`noll_to_nm` gives); any other pair is a ``ValueError``."""
    n, m = integer("n", n, high=MAX_ORDER), abs(integer("m", m))
    if n < 0 or m > n or (n - m) % 2:
        raise ValueError(
            f"a Zernike radial polynomial needs n ≥ 0, |m| ≤ n and n − |m| even, got n={n}, m={m}"
        )
    rho = real_array("rho", rho)
    out = np.zeros_like(rho)
    for s in range((n - m) // 2 + 1):
        c = (
            (-1) ** s
            * factorial(n - s)
            / (factorial(s) * factorial((n + m) // 2 - s) * factorial((n - m) // 2 - s))
        )
        out = out + c * rho ** (n - 2 * s)
    return out


def zernike(j: int, rho, theta):
    """Zernike polynomial ``Z_j(ρ, θ)`` (Noll index ``j``), unit RMS over the unit disk.

    ``Z_j = √(n+1) R_n^0(ρ)`` for ``m = 0`` and ``√(2(n+1)) R_n^|m|(ρ) cos(mθ)``
    (even ``j``) or ``… sin(|m|θ)`` (odd ``j``) otherwise, so that
    ``(1/π) ∫∫_disk Z_i Z_j ρ dρ dθ = δ_ij``.  Z4 is defocus
    ``√3 (2ρ² − 1)``, Z5/Z6 the oblique/vertical astigmatism
    ``√6 ρ² sin 2θ`` / ``√6 ρ² cos 2θ``.  Values outside the disk
    (``ρ > 1``) are returned as computed; mask them with the pupil.

    Parameters
    ----------
    j : int ≥ 1
    rho, theta : array_like
        Polar coordinates (``θ`` in radians); broadcast against each other.

    Examples
    --------
    >>> round(float(zernike(4, 1.0, 0.0)), 6)  # √3
    1.732051
    >>> round(float(zernike(6, 1.0, 0.0)), 6)  # √6
    2.44949
    """
    n, m = noll_to_nm(j)
    rho = real_array("rho", rho, finite=False)
    theta = real_array("theta", theta, finite=False)
    if not (np.all(np.isfinite(rho)) and np.all(np.isfinite(theta))):
        raise ValueError("rho and theta must be finite")
    if np.any(rho < 0):
        raise ValueError("rho must be ≥ 0 (a radius)")
    r = zernike_radial(n, m, rho)
    if m == 0:
        return np.sqrt(n + 1) * r * np.ones_like(theta)
    ang = np.cos(m * theta) if m > 0 else np.sin(-m * theta)
    return np.sqrt(2 * (n + 1)) * r * ang
