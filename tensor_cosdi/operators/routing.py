"""Index maps of sparse operators, from which the structure of ``A Aᵀ`` is derived (SPEC §4)."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Routing"]


@dataclass(frozen=True)
class Routing:
    """Index map of an operator in which every input entry reaches few outputs.

    Used only to derive the *pattern* of ``A Aᵀ``; the values are then probed
    exactly with the operator itself (see :mod:`tensor_cosdi.operators.woodbury`).

    Attributes
    ----------
    key : tuple
        Hashable description of the index map (equal keys ⇔ equal index maps;
        the weights do not enter the key).
    axis_map : tuple
        For every input axis, the output axis it becomes, or ``None`` when the
        axis is summed away.
    disp : tuple
        For every output axis, the interval ``(lo, hi)`` of ``out_index −
        in_index`` along it, or ``None`` when unknown/unbounded.
    spread : tuple
        For every output axis, how far the outputs of one input entry may lie
        apart along it (0: a single output), or ``None`` when unknown.
    single : bool
        Every input entry reaches at most one output entry (then ``A Aᵀ`` is
        diagonal).
    """

    key: tuple
    axis_map: tuple
    disp: tuple
    spread: tuple
    single: bool = True

    @staticmethod
    def identity(ndim: int, key) -> "Routing":
        return Routing(key, tuple(range(ndim)), ((0, 0),) * ndim, (0,) * ndim, True)

    def then(self, outer: "Routing") -> "Routing":
        """Routing of ``outer ∘ self`` (``self`` applied first)."""
        axis_map = tuple(None if m is None else outer.axis_map[m] for m in self.axis_map)
        disp, spread = [], []
        for o in range(len(outer.disp)):
            preimage = [m for m, oo in enumerate(outer.axis_map) if oo == o]
            if len(preimage) != 1:
                disp.append(None)
                spread.append(None)
                continue
            m = preimage[0]
            d1, d2 = self.disp[m], outer.disp[o]
            disp.append(None if d1 is None or d2 is None else (d1[0] + d2[0], d1[1] + d2[1]))
            s1, s2 = self.spread[m], outer.spread[o]
            spread.append(None if s1 is None or s2 is None else s1 + s2)
        return Routing(
            (outer.key, self.key),
            axis_map,
            tuple(disp),
            tuple(spread),
            self.single and outer.single,
        )
