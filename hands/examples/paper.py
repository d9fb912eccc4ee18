"""The paper's example scenes, in the raw scene form (Sections 4.1, 4.3 and 5.1).

* :func:`eq37_scene` - three contacts of Fig. 2, wrench matrix eq. (37): 3S and R1S2 regions, jams (Fig. 3).
* :func:`eq42_scene` - three contacts of Fig. 5, wrench matrix eq. (42): four modes, three at once (Fig. 6).
* :func:`rod_scene` - the thin rod on two moving supports of Fig. 7 (R1S2 / R2S1, Fig. 8).

The numbers are the paper's, printed to three decimals; each function returns
a fresh raw-form dict (see :mod:`qsplan.mechanics.model.scene_io`) that can be written to a
file or passed to :func:`qsplan.mechanics.scene_from_dict`.
"""

from __future__ import annotations

__all__ = ["eq37_scene", "eq42_scene", "rod_scene", "PAPER_SCENES"]

_EQ37_W = [
    [0.804, -0.595, -0.707, -0.707, -0.973, 0.232],
    [0.595, 0.804, 0.707, -0.707, -0.232, -0.973],
    [1.04, -20.9, -3.50, -17.9, 14.0, -7.63],
]
_EQ37_V = [[0.920, -0.391], [0.928, -0.375], [-0.931, -0.367]]

_EQ42_W = [
    [0.966, -0.259, 0.0, -1.0, -0.707, -0.707],
    [0.259, 0.966, 1.0, 0.0, 0.707, -0.707],
    [0.0, -2.0, 0.24, -1.45, 0.75, -1.90],
]
_EQ42_V = [[0.1, 0.995], [0.1, -0.995], [0.1, 0.995]]


def _raw(W, V, mu, g_obj=(0.0, -1.0, 0.0)):
    mus = [mu] * len(V) if isinstance(mu, (int, float)) else list(mu)
    return {
        "g_obj": list(g_obj),
        "contacts": [
            {
                "wn": [W[0][2 * i], W[1][2 * i], W[2][2 * i]],
                "wt": [W[0][2 * i + 1], W[1][2 * i + 1], W[2][2 * i + 1]],
                "mu": float(mus[i]),
                "velocity": list(V[i]),
            }
            for i in range(len(V))
        ],
    }


def eq37_scene(mu=0.3) -> dict:
    """Fig. 2 / eq. (37): ``g_obj = [0, -1, 0]``, ``J_i thetadot`` as printed.

    Parameters
    ----------
    mu : float or sequence of 3 floats
    """
    return _raw(_EQ37_W, _EQ37_V, mu)


def eq42_scene(mu=0.5) -> dict:
    """Fig. 5 / eq. (42): the configuration admitting several modes at once."""
    return _raw(_EQ42_W, _EQ42_V, mu)


def rod_scene(l1=1.0, l2=1.0, mu=(0.3, 0.3), speed=0.1, weight=1.0) -> dict:
    """The thin rod of Fig. 7 on two point supports moving toward each other.

    The rod lies along x with its centre of mass at the origin; support 1 (contact 1)
    is at ``x = -l1``, support 2 at ``x = +l2``; normals point up into the rod
    (``t = (-1, 0)``).  Support 1 moves right, support 2 left, each at ``speed`` (m/s).

    Parameters
    ----------
    l1, l2 : float
        Horizontal distances of the supports from the centre of mass (m), positive.
    mu : (float, float)
        Friction coefficients of contacts 1 and 2.
    speed : float
        Speed of each support (m/s).
    weight : float
        Weight of the rod (N).
    """
    n = (0.0, 1.0)
    return {
        "g_obj": [0.0, -float(weight), 0.0],
        "contacts": [
            {"r": [-float(l1), 0.0], "n": list(n), "mu": float(mu[0]), "velocity": [0.0, -float(speed)]},
            {"r": [float(l2), 0.0], "n": list(n), "mu": float(mu[1]), "velocity": [0.0, float(speed)]},
        ],
    }


PAPER_SCENES = {"eq37": eq37_scene, "eq42": eq42_scene, "rod": rod_scene}
