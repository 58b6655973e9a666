"""The Lytro-CASSI baseline's reconstruction (thesis Section 5.3, after Xiong et al. 2017).

The thesis trains "a dictionary with 2-D patches of size 8 × 8, selecting
10⁴ patches at random" from the Lytro arm's RGB image and uses "a discrete
cosine basis for the spectral dimension".  Here:

* :func:`lytro_dictionary` — K-SVD (:func:`~.dictionary.train_dictionary`)
  on 8 × 8 patches of the R, G and B channels of the measurement's RGB
  frames, 2× over-complete, Kronecker-multiplied with the orthonormal DCT-II
  across the bands: atoms ``d_s ⊗ c_b`` of ``8 × 8 × Nλ`` patches, a
  :class:`~.dictionary.PatchDictionary`;
* ``method="lytro"`` — ADMM with that dictionary as the prior (the ``"dl"``
  method with ``splitting="admm"``), started from OTD.  GAP is not used: the
  two arms make ``A Aᵀ`` ill-conditioned (κ ≈ 10⁸ at 32 × 32 × 8, where
  a CASSI column that sees a single voxel repeats the RGB pixel's
  information), and GAP's ``(AAᵀ + εI)⁻¹`` amplifies the noise along those
  directions; ADMM's ``(AᵀA + ρI)⁻¹`` does not.

The dictionary is learned from the scene's own RGB measurement, never from
its spectra: that is the architecture's side information.
"""

from __future__ import annotations

import numpy as np
import scipy.fft

from ._base import require_system
from .dictionary import PatchDictionary, dictionary_admm, train_dictionary

__all__ = ["lytro_dictionary", "lytro_cassi"]


def lytro_dictionary(
    system, measurement, *, patch: int = 8, n_atoms=None, n_patches: int = 10_000,
    n_iter: int = 10, rng=0, **options,
) -> PatchDictionary:  # fmt: skip
    """The spatial K-SVD dictionary of the RGB arm ⊗ a spectral DCT (see the module).

    Parameters
    ----------
    system : :class:`~tensor_cosdi.systems.LytroCASSI`
    measurement : tensor of ``system.measurement_shape``
    patch, n_atoms, n_patches, n_iter, rng
        Spatial patch side (thesis: 8), spatial atoms (default ``2 · patch²``),
        training patches (thesis: 10⁴, drawn evenly from R, G and B), K-SVD
        iterations and seed.
    options
        ``stride`` and ``max_nonzero`` of the returned dictionary.

    Returns
    -------
    PatchDictionary
        ``n_atoms · Nλ`` atoms of ``patch × patch × Nλ`` entries.
    """
    if getattr(system, "name", None) != "lytro_cassi":
        raise ValueError(
            f"lytro_dictionary needs a LytroCASSI system (its RGB arm), got {type(system).__name__}"
        )
    rgb = system.rgb_image(measurement)
    channels = [rgb[:, :, c : c + 1] / max(float(np.abs(rgb[:, :, c]).max()), 1e-300)
                for c in range(3)]  # fmt: skip
    spatial = train_dictionary(
        channels, patch=patch, n_atoms=n_atoms, n_patches=n_patches, n_iter=n_iter, rng=rng
    )
    nl = system.n_bands
    dct = scipy.fft.idct(np.eye(nl), norm="ortho", axis=0)  # columns: the DCT-II basis vectors
    # PatchDictionary's patch vectors run (row, column, band) with the band fastest
    atoms = np.kron(spatial.atoms, dct)
    return PatchDictionary(atoms, patch, nl, **options)


def lytro_cassi(
    system, measurement, *, dictionary=None, n_patches: int = 10_000, n_iter: int = 10,
    rho: float = 0.15, sigma: float = 0.05, sigma_end: float = 0.01, max_iter: int = 30,
    warm: str = "otd", tol: float = 1e-5, rng=0, nonneg: bool = True, progress: bool = False,
):  # fmt: skip
    """Lytro-CASSI reconstruction: ADMM with the RGB-learned ⊗ DCT dictionary (``"lytro"``).

    ``dictionary`` (a :class:`~.dictionary.PatchDictionary` or a saved one's
    path) skips the training; otherwise :func:`lytro_dictionary` learns it
    from ``measurement`` with ``n_patches`` patches and ``n_iter`` K-SVD
    iterations.  ``rho``, ``sigma``, ``sigma_end``, ``max_iter``, ``warm``,
    ``tol`` and ``nonneg`` (on: each dictionary step projected onto ``≥ 0``) are those of
    the ``"dl"`` method (:func:`~.dictionary.dictionary_admm`).
    """
    require_system("lytro", system)
    if dictionary is None:
        dictionary = lytro_dictionary(
            system, measurement, n_patches=n_patches, n_iter=n_iter, rng=rng
        )
    return dictionary_admm(
        system, measurement, dictionary=dictionary, sigma=sigma, sigma_end=sigma_end,
        max_iter=max_iter, warm=warm, splitting="admm", rho=rho, tol=tol, nonneg=nonneg,
        progress=progress,
    )  # fmt: skip


def _register():
    from ._base import register_method

    register_method(
        "lytro",
        lytro_cassi,
        summary="Lytro-CASSI baseline: ADMM with an RGB-arm K-SVD ⊗ spectral DCT dictionary",
        systems=("lytro_cassi",),
    )


_register()
