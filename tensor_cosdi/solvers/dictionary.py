"""A learned patch dictionary (K-SVD) as a prior: the thesis' DL-3D baseline (Section 5.3).

The thesis compares OTD with "DL": an over-complete dictionary of 3-D
patches (``8 × 8 × N3``, twice as many atoms as a patch has entries) trained
by K-SVD on *other* scenes, in which the cube is sparse.  Here:

* :func:`train_dictionary` — K-SVD (Aharon, Elad & Bruckstein 2006) in its
  approximate form (Rubinstein, Zibulevsky & Elad 2008: one power step per
  atom instead of an SVD) on patches sampled from training cubes; sparse
  coding by Batch-OMP on all patches at once.
* :class:`PatchDictionary` — the trained atoms and the denoiser they define:
  every patch of a grid (stride ``stride``) is coded by OMP until its
  residual is below ``(1.15 σ)²`` per entry (the K-SVD denoising rule),
  and the overlapping patches are averaged back.
* ``method="dl"`` — GAP (the engine) with that denoiser as its prior, σ
  annealed from ``sigma`` to ``sigma_end`` (relative to the start's peak),
  started from 20 GAP-TV iterations.

Any system whose cube is ``(Nx, Ny, C)`` with ``C`` the dictionary's
channels works; the study :func:`tensor_cosdi.studies.c3slfi_table` trains
one on the lenslet (3-D) light fields of the tuning scenes.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.sparse as sp
from numpy.lib.stride_tricks import sliding_window_view

from .. import _backend as B
from ..validate import integer, real_array

__all__ = ["PatchDictionary", "train_dictionary", "dictionary_admm"]

#: The K-SVD denoising constant: code a patch until its residual is below (C σ)² per entry.
NOISE_GAIN = 1.15


def omp(D, Y, *, n_nonzero, tol=None, G=None, chunk: int = 128):
    """Sparse codes ``X (n_atoms, N)`` with ``Y ≈ D X``: orthogonal matching pursuit on all
    columns of ``Y`` at once (Batch-OMP, Rubinstein, Zibulevsky & Elad 2008).

    Each column gets at most ``n_nonzero`` atoms and stops early once its
    squared residual is ``≤ tol``.  Everything works through the Gram
    ``G = DᵀD``: per step one row of ``G`` gathered per column (kept, so the
    correlations are one batched product with the current coefficients),
    the chosen atoms' ``k × k`` Gram grown by that row, and a batch of
    ``k × k`` solves; ``chunk`` columns at a time.  (scikit-learn's
    ``orthogonal_mp_gram`` copies the whole Gram once per column, 126 MB for
    3968 atoms: 16 ms a patch.)  The codes as a dense array; :func:`omp_codes`
    gives them as atom indices and coefficients.
    """
    K, N = D.shape[1], Y.shape[1]
    idx, coef, used = omp_codes(D, Y, n_nonzero=n_nonzero, tol=tol, G=G, chunk=chunk)
    X = np.zeros((K, N))
    for m in range(idx.shape[1]):
        has = np.flatnonzero(used > m)
        np.add.at(X, (idx[has, m], has), coef[has, m])
    return X


def omp_codes(D, Y, *, n_nonzero, tol=None, G=None, chunk: int = 128):
    """:func:`omp`'s codes as ``(idx, coef, used)``: column ``j`` of ``Y`` is
    ``Σ_{m < used[j]} coef[j, m] · D[:, idx[j, m]]`` (``idx``, ``coef`` of shape
    ``(N, n_nonzero)``; entries from ``used[j]`` on are zero).

    Per chunk the columns still being coded are updated in place: the
    correlations of *every* column of the chunk are one batched product with
    views of the kept Gram rows (a column that has stopped is never picked
    again, so its correlations may go stale), which is cheaper than gathering
    the live columns' rows at every step.
    """
    G = D.T @ D if G is None else G
    K, N = D.shape[1], Y.shape[1]
    nz = int(n_nonzero)
    idx_all = np.zeros((N, nz), dtype=np.intp)
    coef_all = np.zeros((N, nz))
    used_all = np.zeros(N, dtype=np.intp)
    for lo in range(0, N, chunk):
        y = Y[:, lo : lo + chunk]
        n = y.shape[1]
        b0 = np.ascontiguousarray((D.T @ y).T)  # (n, K): one row per column of y
        alpha = b0.copy()
        norms = (y * y).sum(axis=0)
        idx, coef = idx_all[lo : lo + n], coef_all[lo : lo + n]
        used = used_all[lo : lo + n]
        rows = np.zeros((n, nz, K))  # G's rows of each column's chosen atoms
        gram = np.zeros((n, nz, nz))  # G restricted to each column's chosen atoms
        live = np.ones(n, dtype=bool) if tol is None else norms > tol
        for k in range(nz):
            a = np.flatnonzero(live)
            if a.size == 0:
                break
            pick = np.argmax(np.abs(alpha[a]), axis=1)
            idx[a, k] = pick
            new = G[pick]
            rows[a, k] = new
            sel = idx[a, : k + 1]
            g_new = np.take_along_axis(new, sel, axis=1)  # G[pick, chosen so far]
            gram[a, k, : k + 1] = g_new
            gram[a, : k + 1, k] = g_new
            b = np.take_along_axis(b0[a], sel, axis=1)
            x = np.linalg.solve(gram[a, : k + 1, : k + 1] + 1e-10 * np.eye(k + 1), b[..., None])
            x = x[..., 0]
            coef[a, : k + 1], used[a] = x, k + 1
            np.subtract(b0, np.matmul(coef[:, None, : k + 1], rows[:, : k + 1])[:, 0], out=alpha)
            if tol is not None:
                live[a[norms[a] - (x * b).sum(axis=1) <= tol]] = False
    return idx_all, coef_all, used_all


class PatchDictionary:
    """An over-complete dictionary of ``patch × patch × channels`` patches and its denoiser.

    Parameters
    ----------
    atoms : array of shape ``(patch² · channels, n_atoms)``
        Columns of unit norm (they are normalised here), patch entries in
        C order ``(row, column, channel)``.
    patch, channels : int
    stride : int, optional
        Grid step of the patches the denoiser codes (default ``patch // 2``;
        the last row and column of patches always touch the border).
    max_nonzero : int, optional
        Most atoms per patch (default 16).

    Calling it, ``D(x, sigma)``, denoises a cube ``(Nx, Ny, channels)`` at
    noise level ``sigma`` (cube units).
    """

    def __init__(self, atoms, patch: int, channels: int, *, stride=None, max_nonzero=None):
        atoms = np.asarray(atoms)
        if atoms.dtype.kind not in "iuf":
            raise ValueError(f"atoms must be real numbers, got dtype {atoms.dtype}")
        atoms = atoms.astype(np.float64)
        self.patch, self.channels = (
            integer("patch", patch, low=1),
            integer("channels", channels, low=1),
        )
        dim = self.patch**2 * self.channels
        if atoms.ndim != 2 or atoms.shape[0] != dim:
            raise ValueError(
                f"atoms must be ({dim}, n_atoms) for {patch}×{patch}×{channels} patches, "
                f"got {atoms.shape}"
            )
        if atoms.shape[1] == 0 or not np.all(np.isfinite(atoms)):
            raise ValueError("atoms must hold at least one column, all of finite values")
        norms = np.linalg.norm(atoms, axis=0)
        if (norms == 0).any():
            raise ValueError("atoms has an all-zero column")
        self.atoms = atoms / norms
        self.stride = (
            max(self.patch // 2, 1) if stride is None else integer("stride", stride, low=1)
        )
        self.max_nonzero = (
            min(16, dim) if max_nonzero is None else integer("max_nonzero", max_nonzero, low=1)
        )

    def _gram(self):
        if getattr(self, "_G", None) is None:
            self._G = self.atoms.T @ self.atoms
        return self._G

    @property
    def n_atoms(self) -> int:
        return self.atoms.shape[1]

    def __repr__(self):
        return (f"PatchDictionary({self.patch}×{self.patch}×{self.channels}, "
                f"{self.n_atoms} atoms, stride {self.stride})")  # fmt: skip

    def save(self, path, *, overwrite: bool = False) -> Path:
        """Write the dictionary as ``.npz`` (refuses to replace a file unless ``overwrite``)."""
        from ..io import atomic_write

        meta = np.array([self.patch, self.channels, self.stride, self.max_nonzero])

        def write(tmp):
            with open(tmp, "wb") as f:
                np.savez(f, atoms=self.atoms, meta=meta)

        return atomic_write(path, write, overwrite=overwrite)

    @classmethod
    def load(cls, path) -> PatchDictionary:
        """A dictionary written by :meth:`save`, read through :func:`tensor_cosdi.io.read_array`
        (sizes checked before anything is allocated, no pickles) and checked as the constructor
        checks its arguments."""
        from ..io.files import read_array, require_file

        path = Path(path)
        require_file(path, "dictionary file")
        if path.suffix.lower() != ".npz":
            raise ValueError(f"{path}: a PatchDictionary file is an .npz written by save()")
        try:
            atoms, meta = read_array(path, "atoms"), read_array(path, "meta")
        except KeyError:
            raise ValueError(
                f"{path} is not a PatchDictionary file (needs atoms and meta)"
            ) from None
        if meta.dtype.kind not in "iu" or meta.shape != (4,):
            raise ValueError(
                f"{path}: 'meta' must be 4 integers (patch, channels, stride, max_nonzero), got "
                f"{meta.dtype} of shape {meta.shape}"
            )
        p, c, s, k = meta.tolist()
        return cls(atoms, p, c, stride=s, max_nonzero=k)

    def _check(self, shape):
        p = self.patch
        if len(shape) != 3 or shape[2] != self.channels or min(shape[:2]) < p:
            raise ValueError(
                f"this dictionary codes {p}×{p}×{self.channels} patches: the cube must be "
                f"(≥{p}, ≥{p}, {self.channels}), got {tuple(shape)}"
            )

    def _grid(self, n):
        g = np.arange(0, n - self.patch + 1, self.stride)
        return g if g[-1] == n - self.patch else np.append(g, n - self.patch)

    def __call__(self, x, sigma):
        xn = real_array("the cube", B.to_numpy(x), finite=False)
        self._check(xn.shape)
        p = self.patch
        rows, cols = self._grid(xn.shape[0]), self._grid(xn.shape[1])
        win = sliding_window_view(xn, (p, p), axis=(0, 1))  # (X, Y, C, p, p)
        Y = win[rows][:, cols].transpose(0, 1, 3, 4, 2).reshape(len(rows) * len(cols), -1).T
        dim = Y.shape[0]
        tol = dim * (NOISE_GAIN * max(float(sigma), 1e-12)) ** 2
        k = min(self.max_nonzero, self.n_atoms)
        idx, coef, _ = omp_codes(self.atoms, Y, n_nonzero=k, tol=tol, G=self._gram())
        # each patch is a handful of atoms: a sparse product, not the dense (atoms × codes)
        codes = sp.csr_matrix(
            (coef.ravel(), idx.ravel(), np.arange(0, coef.size + 1, k)),
            shape=(Y.shape[1], self.n_atoms),
        )
        P = (codes @ self.atoms.T).reshape(len(rows), len(cols), p, p, self.channels)
        out = np.zeros_like(xn)
        weight = np.zeros(xn.shape[:2])
        for i in range(p):  # within one offset the patches' pixels are distinct: plain adds
            for j in range(p):
                at = np.ix_(rows + i, cols + j)
                out[at] += P[:, :, i, j]
                weight[at] += 1.0
        out /= weight[:, :, None]
        return B.tensor_like(out.astype(np.asarray(B.to_numpy(x)).dtype, copy=False), x)


def _sample_patches(cubes, patch, n_patches, rng, align=(1, 1)):
    """``n_patches`` random ``patch × patch × C`` patches (columns), evenly from ``cubes``, their
    corners on multiples of ``align`` (rows, columns)."""
    cubes = [real_array("a training cube", B.to_numpy(c), finite=False) for c in cubes]
    if not cubes:
        raise ValueError("train_dictionary needs at least one training cube")
    chans = {c.shape[2] if c.ndim == 3 else None for c in cubes}
    if len(chans) != 1 or None in chans:
        raise ValueError(
            f"training cubes must all be (Nx, Ny, C) with one C, got {[c.shape for c in cubes]}"
        )
    small = [c.shape for c in cubes if min(c.shape[:2]) < patch]
    if small:
        raise ValueError(f"training cubes smaller than the {patch}×{patch} patch: {small}")
    out = []
    for k, c in enumerate(cubes):
        n = n_patches // len(cubes) + (k < n_patches % len(cubes))
        r = rng.integers(0, (c.shape[0] - patch) // align[0] + 1, n) * align[0]
        s = rng.integers(0, (c.shape[1] - patch) // align[1] + 1, n) * align[1]
        win = sliding_window_view(c, (patch, patch), axis=(0, 1))
        out.append(win[r, s].transpose(0, 2, 3, 1).reshape(n, -1))
    return np.concatenate(out).T


def train_dictionary(
    cubes, *, patch: int = 8, n_atoms=None, sparsity=None, n_patches: int = 6000,
    n_iter: int = 10, rng=0, align=1, progress: bool = False, **options,
) -> PatchDictionary:  # fmt: skip
    """K-SVD on random patches of ``cubes``: the thesis' DL baseline (Section 5.3).

    Parameters
    ----------
    cubes : sequence of arrays ``(Nx, Ny, C)``
        Training scenes — never the scene to be reconstructed (the thesis
        trains on the other light fields).
    patch : int
        Patch side (the thesis: 8).
    n_atoms : int, optional
        Atoms; default twice the patch's entries (the thesis' "2×
        over-complete").
    sparsity : int, optional
        Atoms per training patch in the coding step (default 8).
    n_patches, n_iter, rng
        Training patches, K-SVD iterations, seed.
    align : int or (int, int)
        Training patches start on multiples of ``align`` (rows, columns);
        default 1, anywhere.  On a C3SLFI lenslet image whose lenslets hold
        ``views`` pixels, ``align=views`` makes every training patch a whole
        number of lenslets — the 5-D patch of the thesis' DL-5D (scene points
        × every view × bands) — and the coding grid must then stay aligned
        too (a ``stride`` that is a multiple of ``align``; refused otherwise).
    options
        ``stride`` and ``max_nonzero`` of the returned :class:`PatchDictionary`.

    Returns
    -------
    PatchDictionary

    Examples
    --------
    >>> import numpy as np
    >>> from tensor_cosdi.solvers.dictionary import train_dictionary
    >>> cube = np.random.default_rng(0).random((16, 16, 3))
    >>> train_dictionary([cube], patch=4, n_patches=300, n_iter=2)
    PatchDictionary(4×4×3, 96 atoms, stride 2)
    """
    from tqdm.auto import tqdm

    rng = B.default_rng(rng)
    patch = integer("patch", patch, low=1)
    n_iter = integer("n_iter", n_iter, low=1)
    n_patches = integer("n_patches", n_patches, low=1)
    pair = tuple(np.broadcast_to(np.asarray(align, dtype=object), (2,)))
    if any(isinstance(a, bool) or not isinstance(a, (int, np.integer)) or a < 1 for a in pair):
        raise ValueError(f"align must be a positive integer or a pair of them, got {align!r}")
    pair = tuple(int(a) for a in pair)
    stride = options.get("stride", max(patch // 2, 1))
    if pair != (1, 1) and any(int(stride) % a for a in pair):
        raise ValueError(
            f"the coding stride {stride} must be a multiple of align {pair} so that coded "
            "patches stay aligned as the training patches are"
        )
    Y = _sample_patches(cubes, patch, int(n_patches), rng, pair)
    dim, n = Y.shape
    k = 2 * dim if n_atoms is None else integer("n_atoms", n_atoms, low=1)
    s = min(8, dim) if sparsity is None else integer("sparsity", sparsity, low=1)
    if not 1 <= s <= min(dim, k) or k < 1:
        raise ValueError(f"need 1 ≤ sparsity ≤ min(patch entries, atoms) = {min(dim, k)}; got {s}")
    D = Y[:, rng.choice(n, size=k, replace=k > n)].copy()
    D += 1e-6 * rng.standard_normal(D.shape)  # repeated draws must not give equal atoms
    D /= np.linalg.norm(D, axis=0)
    for _ in tqdm(range(int(n_iter)), desc="K-SVD", disable=not progress):
        X = omp(D, Y, n_nonzero=s)
        R = Y - D @ X
        energy = (R * R).sum(axis=0)  # each patch's residual, kept current below
        for j in rng.permutation(k):
            users = np.flatnonzero(X[j])
            if users.size == 0:  # unused atom: the worst-coded patch instead
                worst = int(np.argmax(energy))
                D[:, j] = Y[:, worst] / max(np.linalg.norm(Y[:, worst]), 1e-12)
                continue
            E = R[:, users] + np.outer(D[:, j], X[j, users])
            d = E @ X[j, users]  # one power step of the rank-1 SVD of E (approximate K-SVD)
            d /= max(np.linalg.norm(d), 1e-12)
            x = E.T @ d
            D[:, j], X[j, users] = d, x
            R[:, users] = E - np.outer(d, x)
            energy[users] = (R[:, users] * R[:, users]).sum(axis=0)
    return PatchDictionary(D, patch, Y.shape[0] // patch**2, **options)


def dictionary_admm(
    system, measurement, *, dictionary=None, sigma=0.05, sigma_end=0.01, max_iter=30,
    warm="gap_tv", warm_iter="auto", accelerate="auto", eps="auto", splitting="gap", rho=0.15,
    tol=1e-5, nonneg=True, progress=False,
):  # fmt: skip
    """GAP (or ADMM) with a K-SVD patch dictionary as its prior (registered as ``"dl"``).

    ``dictionary`` is a :class:`PatchDictionary` or the path of one saved
    with :meth:`PatchDictionary.save`; train it on other scenes with
    :func:`train_dictionary`.  ``splitting="admm"`` replaces GAP's
    ``(AAᵀ + εI)⁻¹`` projection by ADMM's ``(AᵀA + ρI)⁻¹`` step (``ρ = rho``
    relative to the sensing gain), which does not amplify noise along the
    weak directions of an ill-conditioned ``A Aᵀ`` (Lytro-CASSI, κ ≈ 10⁸);
    ``warm`` is ``"gap_tv"``, ``"otd"`` or ``"none"``, ``warm_iter`` the start's iterations
    (``"auto"``: 20 of GAP-TV, OTD's own; see :func:`~.pnp_gap.pnp_gap`); ``nonneg`` (on) keeps each
    denoised estimate non-negative (off for a signed cube).
    """
    from ._base import check_positive
    from .pnp_gap import gap_settings, warm_started_gap
    from .priors import Denoiser

    if dictionary is None:
        raise ValueError(
            "method 'dl' needs dictionary=: a PatchDictionary trained on other scenes "
            "(tensor_cosdi.solvers.dictionary.train_dictionary) or the path of a saved one"
        )
    if isinstance(dictionary, (str, Path)):
        dictionary = PatchDictionary.load(dictionary)
    if not isinstance(dictionary, PatchDictionary):
        raise TypeError(f"dictionary must be a PatchDictionary or a path, got {type(dictionary)}")
    if splitting not in ("gap", "admm"):
        raise ValueError(f"splitting must be 'gap' or 'admm', got {splitting!r}")
    check_positive("rho", rho)
    if not isinstance(nonneg, (bool, np.bool_)):
        raise ValueError(f"nonneg must be True or False, got {nonneg!r}")
    dictionary._check(tuple(system.cube_shape))
    accelerate, eps, _ = gap_settings(system, measurement, accelerate, eps)
    prior = Denoiser(dictionary, sigma=sigma, sigma_end=sigma_end, n_steps=max_iter, nonneg=nonneg)
    return warm_started_gap(
        system, measurement, prior, warm=warm,
        warm_iter=20 if warm == "gap_tv" and warm_iter == "auto" else warm_iter,
        accelerate=accelerate,
        eps=eps, max_iter=max_iter, tol=tol, progress=progress,
        desc="K-SVD dictionary " + splitting.upper(), rho=rho if splitting == "admm" else None,
    )  # fmt: skip


def _register():
    from ._base import register_method

    register_method(
        "dl",
        dictionary_admm,
        summary="GAP with a K-SVD patch dictionary learned on other scenes (thesis' DL baseline)",
        needs={
            "dictionary": "a PatchDictionary trained on other scenes "
            "(tensor_cosdi.solvers.dictionary.train_dictionary) or the path of a saved one"
        },
    )


_register()
