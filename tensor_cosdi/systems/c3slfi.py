"""C3SLFI: colour-coded compressive spectral light field imaging (SPEC §3.3, thesis Ch. 5)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import tensorly as tl

from .. import _backend as B
from ..codes import complementary_colour_codes
from ..operators import LAYOUTS, Code, LightFieldLayout, ModeProduct, Stack, SumAxis
from ..validate import flag, real_array
from ._base import System, as_code, count, wavelengths_for

__all__ = ["C3SLFI"]

FORMS = ("3d", "5d")


def _views(views):
    if views is None:
        return None
    try:
        n4, n5 = (int(v) for v in views)
    except (TypeError, ValueError):
        raise ValueError(
            f"views must be a pair of positive integers (N4, N5), got {views!r}"
        ) from None
    if n4 < 1 or n5 < 1 or tuple(views) != (n4, n5):
        raise ValueError(f"views must be a pair of positive integers (N4, N5), got {views!r}")
    return n4, n5


def _np_forward(layout: LightFieldLayout, x: np.ndarray) -> np.ndarray:
    """The layout permutation on a NumPy parameter array (any active backend)."""
    return np.transpose(x, layout.permutation()).reshape(layout.output_shape)


def _np_adjoint(layout: LightFieldLayout, y: np.ndarray) -> np.ndarray:
    return np.transpose(y.reshape(layout.split_shape()), tuple(np.argsort(layout.permutation())))


class C3SLFI(System):
    """K colour-coded snapshots of a spectral light field, per-voxel sensing, no shear.

    ``G[i1, i2, k, i4, i5] = Σ_l T[i1, i2, l, i4, i5, k] F[i1, i2, l, i4, i5]``
    (5-D form) or, on the lenslet (3-D) parameterisation of Eq. 85,
    ``G̃[j1, j2, k] = Σ_l T̃[j1, j2, l, k] F̃[j1, j2, l]``.

    Parameters
    ----------
    codes : array_like of shape ``cube_shape + (K,)``
        Colour-coded apertures ``T`` (transmittances in ``[0, 1]``):
        ``(Ñ1, Ñ2, N3, K)`` for ``layout="3d"``, ``(N1, N2, N3, N4, N5, K)``
        for ``layout="5d"``.  See :func:`tensor_cosdi.codes.complementary_colour_codes`.
    layout : {"3d", "5d"}
        ``"3d"``: cube ``(Ñ1, Ñ2, N3)`` = the lenslet image (``Ñ1 = N1·N4``,
        ``Ñ2 = N2·N5``), measurement ``(Ñ1, Ñ2, K)``.  ``"5d"``: cube
        ``(N1, N2, N3, N4, N5)``, measurement ``(N1, N2, K, N4, N5)``.
    views : (N4, N5), optional
        Views per lenslet of a ``"3d"`` system; needed for the conversions to
        5-D (:meth:`to_5d`, :meth:`as_5d`).  Implied by a ``"5d"`` cube.
    raw_layout : {"interleaved", "tiled"}
        How the 3-D image holds the views: ``"interleaved"`` (Eq. 85, a
        lenslet's pixels hold the views of one scene point; the
        parameterisation OTD-3D works on) or ``"tiled"`` (Eq. 78 as fixed in
        SPEC §12, each view a contiguous sub-image).
    complementary : bool
        Require ``Σ_k T[..., k] = 1`` for every voxel (default): Lemma 1 then
        gives the panchromatic light field exactly, and the thesis' method
        depends on it.  Non-complementary codes are an error unless this is
        ``False``.
    wavelengths : sequence of float, optional

    Notes
    -----
    ``A Aᵀ`` is block-diagonal with one ``K × K`` block per pixel,
    ``Q[k1, k2] = Σ_l T[…, l, k1] T[…, l, k2]`` (Eq. 209-211), so the
    Woodbury step is a batch of ``K × K`` solves.  Spatially invariant codes
    are the separable n-mode form of Eq. 80, ``G = F ×₃ Φ3`` — build those with
    :meth:`separable`.

    Examples
    --------
    >>> from tensor_cosdi.codes import complementary_colour_codes
    >>> from tensor_cosdi.systems import C3SLFI
    >>> T = complementary_colour_codes((8, 6, 5), 2, rng=0)
    >>> sys = C3SLFI(T, layout="3d", views=(2, 2))
    >>> sys.cube_shape, sys.measurement_shape, sys.as_5d().cube_shape
    ((8, 6, 5), (8, 6, 2), (4, 3, 5, 2, 2))
    """

    #: Over-relaxed ADMM cost PSNR here on every scene checked (30 dB, 64×64×16:
    #: ``benchmarks/results/relax_c3slfi.md``), so ``relax="auto"`` keeps plain ADMM.
    admm_relax = False

    def __init__(
        self,
        codes,
        *,
        layout="3d",
        views=None,
        raw_layout="interleaved",
        complementary=True,
        wavelengths=None,
        _phi=None,
    ):
        if layout not in FORMS:
            raise ValueError(f"layout must be one of {FORMS}, got {layout!r}")
        if raw_layout not in LAYOUTS:
            raise ValueError(f"raw_layout must be one of {LAYOUTS}, got {raw_layout!r}")
        self.layout = layout
        self.raw_layout = raw_layout
        if _phi is None:
            self.codes = as_code(codes, "codes", (4,) if layout == "3d" else (6,))
        else:
            self.codes = codes  # read-only broadcast view built by separable()
        self.phi = _phi
        cube = self.codes.shape[:-1]
        K = self.codes.shape[-1]
        if layout == "5d":
            if views is not None and _views(views) != cube[3:]:
                raise ValueError(f"views={views!r} contradicts the 5-D codes' view axes {cube[3:]}")
            self.views = cube[3:]
        else:
            self.views = _views(views)
            if self.views is not None and (cube[0] % self.views[0] or cube[1] % self.views[1]):
                raise ValueError(
                    f"views {self.views} do not divide the 3-D image {cube[:2]}: Ñ1 = N1·N4 and "
                    "Ñ2 = N2·N5 must be multiples of the views"
                )
        self.complementary = flag("complementary", complementary)
        if self.complementary:
            if K < 2:
                raise ValueError(
                    f"complementary colour coding needs K ≥ 2 snapshots, got K = {K} "
                    "(pass complementary=False for a single coded snapshot)"
                )
            total = np.sum(self.codes, axis=-1)
            err = np.abs(total - 1.0)
            if err.max() > 1e-9:
                worst = np.unravel_index(int(np.argmax(err)), err.shape)
                raise ValueError(
                    "codes are not complementary: Σ_k T[..., k] must be 1 for every voxel "
                    f"(Lemma 1), but it is {total[worst]:g} at index "
                    f"{tuple(int(i) for i in worst)}; "
                    "pass complementary=False to allow this"
                )
        if _phi is not None:
            op = ModeProduct(cube, {2: _phi})
        else:
            ops = [SumAxis(cube, 2) @ Code(self.codes[..., k], cube) for k in range(K)]
            op = Stack(ops, axis=2)
        axes = ("x", "y", "λ") if layout == "3d" else ("x", "y", "λ", "u", "v")
        self._finish(
            op,
            wavelengths=wavelengths_for(wavelengths, cube[2]),
            axes=axes,
            measurement_axes=tuple("k" if a == "λ" else a for a in axes),
        )

    @property
    def n_snapshots(self) -> int:
        return self.codes.shape[-1]

    # ---- roles (systems/_roles.py) -------------------------------------------------------
    name = "c3slfi"
    demo_scene = "astronaut"
    demo_options = {"views": (4, 4)}
    has_depth = True
    example_options = {"views": (4, 4), "n_snapshots": 4, "max_disparity": 1.0}
    #: The SNR estimate's GAP-TV fit weight (``System.snr_fit_tv``): chosen by 4-fold
    #: cross-validation over the 28 tuning scenes at 64×64×16 and 128×128×28, noiseless / 30 /
    #: 20 dB (``benchmarks/results/snr_fit_tv_c3slfi.md``): 166 of 168 estimates ok, against
    #: 155 at the general 0.1, which read clean scenes at 30-31 dB and a true 30 dB at 26-27.
    snr_fit_tv = 0.05

    @property
    def depth_kind(self):
        return None if self.views is None else "disparity"

    def _state(self):
        if self.phi is not None:
            raise ValueError(
                "a separable C3SLFI (C3SLFI.separable) is saved by its Φ3 matrix, which bundles do "
                "not "
                "support yet; build it with explicit codes to save it"
            )
        return (
            {
                "layout": self.layout,
                "raw_layout": self.raw_layout,
                "complementary": bool(self.complementary),
                "views": None if self.views is None else [int(v) for v in self.views],
            },
            {"codes": np.asarray(self.codes)},
        )

    @classmethod
    def _from_state(cls, params, arrays):
        views = params.pop("views", None)
        return cls(
            arrays["codes"],
            views=None if views is None else tuple(views),
            wavelengths=arrays["wavelengths"],
            **params,
        )

    @property
    def frame_count(self) -> int:
        return self.n_snapshots

    def frames_to_measurement(self, frames):
        """``K`` raw lenslet frames (snapshot order, :attr:`raw_layout`) → the measurement (3-D or
        5-D)."""
        from ._roles import stack_frames

        a = stack_frames(frames)
        shape = tuple(self.measurement_shape)
        if self.layout == "3d":
            if a.shape != shape:
                raise ValueError(
                    f"C3SLFI frames: expected {shape[2]} frames of {shape[:2]}, got {a.shape}"
                )
            return a
        g3_shape = (shape[0] * shape[3], shape[1] * shape[4], shape[2])
        if a.shape != g3_shape:
            raise ValueError(
                f"C3SLFI frames: expected {g3_shape[2]} lenslet frames of {g3_shape[:2]}, got "
                f"{a.shape}"
            )
        return np.asarray(self._layout(self.n_snapshots).adjoint(a))

    def measurement_to_frames(self, measurement):
        g = self._frames_check(measurement)
        return np.asarray(self.measurement_to_3d(g)) if self.layout == "5d" else g

    def depth_from_cube(self, cube, *, n_steps: int = 4, max_disparity: float = 2.0):
        """Disparity (px per view step) of the centre view, over all bands; ``None`` without
        views."""
        from ._roles import views_disparity

        if self.layout == "3d" and self.views is None:
            return None
        return views_disparity(self.to_5d(cube), max_disparity)

    def spectral_view(self, cube):
        """The centre view of the light field."""
        five = np.asarray(self.to_5d(real_array("cube", cube, finite=False)))
        return five[:, :, :, five.shape[3] // 2, five.shape[4] // 2]

    @classmethod
    def _example(cls, scene, shape, wl, seed, shifts, views, n_snapshots, max_disparity):
        from .. import scenes
        from ..operators import validate_shape

        nx, ny = shape
        n4, n5 = validate_shape(views, "views")
        if nx % n4 or ny % n5:
            raise ValueError(f"c3slfi: shape {shape} must be divisible by views {views}")
        if shifts != 1:
            raise ValueError("c3slfi has no dispersion: shifts does not apply")
        centre = scenes.scene_cube(scene, (nx // n4, ny // n5), wl)
        _, disp = scenes.motorcycle((nx // n4, ny // n5), [550.0])
        d = (disp - disp.mean()) / max(np.abs(disp - disp.mean()).max(), 1e-12) * max_disparity
        lf = scenes.light_field(centre, d, views=(n4, n5))
        system = cls.example(
            (nx, ny, len(wl)), rng=seed, n_snapshots=n_snapshots, views=(n4, n5), wavelengths=wl
        )
        lf = lf if B.backend_name() == "numpy" else B.as_tensor(lf, np.asarray(lf).dtype.name)
        return system, B.to_numpy(system.to_3d(lf)), centre, d, {}

    @classmethod
    def separable(
        cls,
        phi,
        cube_shape,
        *,
        views=None,
        raw_layout="interleaved",
        complementary=True,
        wavelengths=None,
    ):
        """Spatially invariant spectral codes, the n-mode form ``G = F ×₃ Φ3`` (Equation 80).

        Parameters
        ----------
        phi : array_like of shape (K, N3)
            ``Φ3[k, l]``: transmission of band ``l`` in snapshot ``k``.
        cube_shape : ``(Ñ1, Ñ2, N3)`` or ``(N1, N2, N3, N4, N5)``
            Chooses the 3-D or 5-D form.
        """
        phi = as_code(phi, "phi", (2,))
        shape = tuple(int(n) for n in cube_shape)
        if len(shape) not in (3, 5) or any(n < 1 for n in shape):
            raise ValueError(f"cube_shape must have 3 or 5 positive sizes, got {cube_shape!r}")
        if phi.shape[1] != shape[2]:
            raise ValueError(
                f"phi of shape {phi.shape} needs (K, N3) with N3 = {shape[2]} bands of cube_shape "
                f"{shape}"
            )
        t = phi.T.reshape((1, 1, shape[2]) + (1,) * (len(shape) - 3) + (phi.shape[0],))
        codes = np.broadcast_to(t, shape + (phi.shape[0],))
        return cls(
            codes,
            layout="3d" if len(shape) == 3 else "5d",
            views=views,
            raw_layout=raw_layout,
            complementary=complementary,
            wavelengths=wavelengths,
            _phi=phi,
        )

    @classmethod
    def example(
        cls,
        cube_shape=None,
        *,
        rng=0,
        n_snapshots: int = 2,
        n_filters=None,
        views=None,
        **overrides,
    ):
        """A seeded instance with complementary colour codes.

        ``cube_shape`` of 3 axes (default ``(8, 8, 6)`` with ``views=(2, 2)``)
        gives the 3-D form, of 5 axes the 5-D form.
        """
        shape = (8, 8, 6) if cube_shape is None else tuple(cube_shape)
        if len(shape) == 3 and views is None and cube_shape is None:
            views = (2, 2)
        codes = complementary_colour_codes(
            shape, count(n_snapshots, "n_snapshots", 2), n_filters=n_filters, rng=rng
        )
        layout = "3d" if len(shape) == 3 else "5d"
        return cls(codes, layout=layout, views=views, **overrides)

    # ---- Lemma 1 ---------------------------------------------------------------------
    @property
    def panchromatic_exact(self) -> bool:
        """True with complementary codes (Lemma 1)."""
        return bool(self.complementary)

    def panchromatic(self, measurement, *, mu: float = 1e-2):
        """Panchromatic light field ``Z = Σ_l F``.

        With complementary codes this is Lemma 1 (Eq. 89), exact and free:
        ``Z = Σ_k G[..., k, ...]``.  Otherwise the regularised least-squares
        estimate of :meth:`System.panchromatic` (``mu`` is its weight).
        """
        g = self.check_measurement(measurement, "panchromatic")
        if self.complementary:
            return tl.sum(g, axis=2)
        return super().panchromatic(g, mu=mu)

    # ---- 3-D ↔ 5-D -------------------------------------------------------------------
    def _shape5(self):
        if self.layout == "5d":
            return self.cube_shape
        if self.views is None:
            raise ValueError("this 3-D C3SLFI has no views=(N4, N5); pass views to convert to 5-D")
        (n1t, n2t, n3), (n4, n5) = self.cube_shape, self.views
        return (n1t // n4, n2t // n5, n3, n4, n5)

    def _layout(self, mid: int):
        s = self._shape5()
        return LightFieldLayout(s[:2] + (mid,) + s[3:], self.raw_layout)

    def to_5d(self, cube):
        """A cube of this system → the 5-D light field ``(N1, N2, N3, N4, N5)`` (exact
        permutation)."""
        return cube if self.layout == "5d" else self._layout(self.cube_shape[2]).adjoint(cube)

    def to_3d(self, cube):
        """A 5-D light field → this system's 3-D image ``(Ñ1, Ñ2, N3)`` in :attr:`raw_layout`."""
        return self._layout(self._shape5()[2]).forward(cube)

    def measurement_to_5d(self, measurement):
        """Measurement ``(Ñ1, Ñ2, K)`` → ``(N1, N2, K, N4, N5)`` (identity for a 5-D system)."""
        if self.layout == "5d":
            return measurement
        return self._layout(self.n_snapshots).adjoint(measurement)

    def measurement_to_3d(self, measurement):
        """Measurement ``(N1, N2, K, N4, N5)`` → ``(Ñ1, Ñ2, K)`` in :attr:`raw_layout`."""
        return self._layout(self.n_snapshots).forward(measurement)

    def _converted(self, layout, raw_layout, convert):
        kw = dict(
            raw_layout=raw_layout, complementary=self.complementary, wavelengths=self.wavelengths
        )
        shape5 = self._shape5()
        if self.phi is not None:
            target = (
                shape5
                if layout == "5d"
                else (shape5[0] * shape5[3], shape5[1] * shape5[4], shape5[2])
            )
            return C3SLFI.separable(self.phi, target, views=shape5[3:], **kw)
        codes = np.stack([convert(self.codes[..., k]) for k in range(self.n_snapshots)], axis=-1)
        return C3SLFI(codes, layout=layout, views=shape5[3:], **kw)

    def as_5d(self):
        """The same system on the 5-D light field (codes permuted accordingly)."""
        if self.layout == "5d":
            return self
        lay = self._layout(self.cube_shape[2])
        return self._converted("5d", self.raw_layout, lambda c: _np_adjoint(lay, c))

    def as_3d(self, raw_layout=None):
        """The same system on the 3-D lenslet image in ``raw_layout`` (default
        :attr:`raw_layout`)."""
        raw_layout = self.raw_layout if raw_layout is None else raw_layout
        if raw_layout not in LAYOUTS:
            raise ValueError(f"raw_layout must be one of {LAYOUTS}, got {raw_layout!r}")
        five = self.as_5d()
        s = five.cube_shape
        lay = LightFieldLayout(s, raw_layout)
        return five._converted("3d", raw_layout, lambda c: _np_forward(lay, c))

    # ---- explicit matrix (Eq. 80, 206-207) ----------------------------------------
    def matrix(self):
        cube = self.cube_shape
        n1, n2, n3 = cube[:3]
        nv = int(np.prod(cube[3:]))  # N4·N5 (1 in 3-D)
        K = self.n_snapshots
        if self.phi is not None:
            # Eq. 80: vec(F ×₃ Φ3) = (I_{N4N5} ⊗ Φ3 ⊗ I_{N1N2}) vec(F)
            return sp.kron(
                sp.identity(nv), sp.kron(sp.csr_matrix(self.phi), sp.identity(n1 * n2))
            ).tocsr()
        # Eq. 206-207: snapshot k is [diag(t_{0,k}) … diag(t_{N3−1,k})] for every view
        p = n1 * n2
        T = np.asarray(self.codes).reshape((p, n3, nv, K), order="F")
        u, l, v, k = np.meshgrid(
            np.arange(p), np.arange(n3), np.arange(nv), np.arange(K), indexing="ij"
        )
        rows = u + p * k + p * K * v
        cols = u + p * l + p * n3 * v
        return sp.csr_matrix(
            (T.ravel(), (rows.ravel(), cols.ravel())), shape=(p * K * nv, p * n3 * nv)
        )
