"""Building described hands (:class:`qsplan.hands.described.hand.DescribedHand`): from a description, from today's
records, from a plan's metadata, and the door that converts any of them (:func:`as_hand`; :func:`record_of` for the
record that answers a bare record).  The door is the one place that asks which record type a value is (issue 32):
past it, a hand's record answers for itself.  Units SI (m, kg, rad).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from qsplan.hands.described.hand import DescribedHand
from qsplan.mechanics.errors import QsplanError

__all__ = ["as_hand", "described_from_chain", "described_from_two_finger", "hand_from_metadata", "make_described_hand",
           "record_from_metadata", "record_of"]


def _user_maps(chain) -> tuple:
    from qsplan.hands.paper_hand.grasps import user_edge, user_vertex

    k = len(chain.workpiece)
    return (np.array([user_vertex(chain, i) for i in range(k)], dtype=int),
            np.array([user_edge(chain, i) for i in range(k)], dtype=int))  # fmt: skip


def described_from_chain(chain, accelerated: bool = True, own_limits="description") -> DescribedHand:
    """A :class:`~qsplan.hands.chains.hand.ChainHand` as a :class:`DescribedHand` (the paper's closed forms where its
    description has the paper's form and ``accelerated``).  ``own_limits``: the description's by default."""
    from qsplan.hands.described.scenes import contact_view
    from qsplan.hands.description.two_finger_form import two_finger_parameters
    from qsplan.hands.paper_hand.two_finger import TwoFingerHand

    desc = chain.description
    params = two_finger_parameters(desc)
    paper = None if params is None else TwoFingerHand(chain.workpiece, chain.workpiece_mass, mu=chain.mu,
                                                      vertex_order=chain.vertex_order,
                                                      vertex_of_user=chain.vertex_of_user, **params)  # fmt: skip
    limits = (desc.joint_limits, desc.joint_speeds) if own_limits == "description" else own_limits
    return DescribedHand(desc, chain.workpiece, chain.workpiece_mass, chain.mu, chain.vertex_order, chain.vertex_of_user,
                         limits, bool(accelerated and paper is not None), chain, paper, contact_view(desc),
                         *_user_maps(chain))  # fmt: skip


def make_described_hand(description, workpiece, workpiece_mass=0.2, mu=0.2, palm_edge=None,
                        accelerated: bool = True) -> DescribedHand:  # fmt: skip
    """Validate and build a :class:`DescribedHand`.

    Parameters
    ----------
    description : qsplan.hands.description.HandDescription
    workpiece : array-like, shape (k, 2)
        Convex polygon (m) (:func:`qsplan.hands.geometry.workpiece.prepare_workpiece`).
    workpiece_mass : float
        kg, positive.
    mu : float
        Friction coefficient, nonnegative.
    palm_edge : int, optional
        The edge, as written, that rests on the palm.
    accelerated : bool
        Let the paper's closed forms answer where the description has the paper's form.

    Raises
    ------
    SceneError
        Naming the field.
    """
    from qsplan.hands.chains.hand import make_chain_hand

    return described_from_chain(make_chain_hand(description, workpiece, workpiece_mass, mu, palm_edge), accelerated)


@lru_cache(maxsize=1)
def _paper_file_limits() -> tuple:
    """The bundled paper hand file's joint range (rad) and speed (rad/s) (``hands/data/paper_hand.toml``)."""
    from qsplan.hands.description.files import load_hand

    desc = load_hand("paper_hand")
    return tuple(float(v) for v in desc.joint_limits[0]), float(desc.joint_speeds[0])


def described_from_two_finger(hand, joint_limits=None, joint_speed=None, accelerated: bool = True) -> DescribedHand:
    """The paper's :class:`~qsplan.hands.paper_hand.two_finger.TwoFingerHand` (its parameters) as a
    :class:`DescribedHand`.

    Parameters
    ----------
    hand : TwoFingerHand
    joint_limits : array-like, shape (2,) or (2, 2), optional
        The fingers' ranges (rad) the generic closing closes within; default the bundled paper hand file's.
    joint_speed : float or array-like, shape (2,), optional
        rad/s; default the bundled paper hand file's.
    accelerated : bool

    Notes
    -----
    ``own_limits`` is None: a hand given by its parameters has none (a task's ``[limits]`` give them).
    """
    from qsplan.hands.chains.hand import ChainHand
    from qsplan.hands.described.scenes import contact_view
    from qsplan.hands.description.two_finger_form import describe_two_finger_hand

    lim, speed = _paper_file_limits()
    desc = describe_two_finger_hand(hand, lim if joint_limits is None else joint_limits,
                                    speed if joint_speed is None else joint_speed, name="paper hand")  # fmt: skip
    k = len(hand.workpiece)
    order = hand.vertex_order if hand.vertex_order is not None else tuple(range(k))
    of_user = hand.vertex_of_user if hand.vertex_of_user is not None else tuple(range(k))
    chain = ChainHand(desc, hand.workpiece, hand.workpiece_mass, hand.mu, order, of_user)
    return DescribedHand(desc, hand.workpiece, hand.workpiece_mass, hand.mu, order, of_user, None, bool(accelerated),
                         chain, hand, contact_view(desc), *_user_maps(chain))  # fmt: skip


def record_from_metadata(meta) -> object:
    """The hand record a plan's ``metadata["hand"]`` records (:meth:`DescribedHand.metadata`): a
    :class:`~qsplan.hands.chains.hand.ChainHand` when it holds a ``description``, else the paper's
    :class:`~qsplan.hands.paper_hand.two_finger.TwoFingerHand` (whose palm thickness is not recorded: the default).

    Raises
    ------
    QsplanError
        Naming the field (``hand.description.fingers[0]...``, ``hand.workpiece_vertices_m``).
    """
    if not isinstance(meta, dict):
        raise QsplanError(f"hand: expected the metadata's hand table; got {type(meta).__name__}")
    try:
        if "description" in meta:
            from qsplan.hands.chains.hand import make_chain_hand
            from qsplan.hands.description.files import hand_from_table

            desc = hand_from_table(meta["description"], field="hand.description",
                                   source=str(meta.get("description_source", "plan metadata")))  # fmt: skip
            return make_chain_hand(desc, meta["workpiece_vertices_m"], meta["workpiece_mass_kg"], meta.get("mu", 0.2))
        from qsplan.hands.paper_hand.two_finger import make_two_finger_hand

        return make_two_finger_hand(meta["workpiece_vertices_m"], meta["workpiece_mass_kg"], meta["finger_base_m"],
                                    meta["finger_length_m"], meta["finger_width_m"], meta["finger_mass_kg"],
                                    meta["palm_halfwidth_m"], gravity=meta["gravity_m_s2"])  # fmt: skip
    except KeyError as exc:
        raise QsplanError(f"hand.{exc.args[0]}: missing from the plan's metadata") from None
    except QsplanError as exc:
        text = str(exc)
        raise QsplanError(text if text.startswith("hand") else f"hand.{text}") from None


def hand_from_metadata(meta, accelerated: bool = True) -> DescribedHand:
    """The hand a plan's ``metadata["hand"]`` records (:meth:`DescribedHand.metadata`): its record
    (:func:`record_from_metadata`) through the door (:func:`as_hand`).

    Raises
    ------
    QsplanError
        Naming the field (:func:`record_from_metadata`).
    """
    return as_hand(record_from_metadata(meta), accelerated=accelerated)


def as_hand(hand, own_limits=None, accelerated: bool = True):
    """``hand`` as a :class:`~qsplan.hands.described.hand.DescribedHand` (the door: today's records converted once).

    A DescribedHand is returned as is; a :class:`~qsplan.hands.paper_hand.two_finger.TwoFingerHand` (the paper's hand by
    its parameters) or a :class:`~qsplan.hands.chains.hand.ChainHand` is converted
    (:func:`described_from_two_finger`, :func:`described_from_chain`), the paper's closed forms answering where
    ``accelerated`` and the hand has the paper's form.
    ``own_limits``: ``(ranges (n_j, 2), speeds (n_j,))`` the hand states (its file's), replacing the converted ones.

    Raises
    ------
    QsplanError
        Naming ``hand`` for anything else.
    """
    from dataclasses import replace

    from qsplan.hands.chains.hand import ChainHand
    from qsplan.hands.paper_hand.two_finger import TwoFingerHand

    if isinstance(hand, DescribedHand):
        out = hand
    elif isinstance(hand, TwoFingerHand):
        out = described_from_two_finger(hand, accelerated=accelerated)
    elif isinstance(hand, ChainHand):
        out = described_from_chain(hand, accelerated)
    else:
        raise QsplanError(f"hand: expected a DescribedHand, a TwoFingerHand or a ChainHand; got {type(hand).__name__}")
    return out if own_limits is None else replace(out, own_limits=own_limits)


def record_of(hand):
    """The record that answers ``hand`` (:class:`qsplan.hands.protocol.HandRecord`), as the hand records always
    answered: a described hand's own (:attr:`DescribedHand.record`); a bare
    :class:`~qsplan.hands.paper_hand.two_finger.TwoFingerHand` by the paper's closed forms
    (:class:`~qsplan.hands.paper_hand.record.PaperRecord`); a bare :class:`~qsplan.hands.chains.hand.ChainHand` by its
    description, whatever its form (:class:`~qsplan.hands.chains.record.ChainRecord`).  The door of
    :mod:`qsplan.hands.described.records`' functions.

    Raises
    ------
    QsplanError
        Naming ``hand`` for anything else.
    """
    from qsplan.hands.chains.hand import ChainHand
    from qsplan.hands.chains.record import ChainRecord
    from qsplan.hands.paper_hand.record import PaperRecord
    from qsplan.hands.paper_hand.two_finger import TwoFingerHand

    if isinstance(hand, DescribedHand):
        return hand.record
    if isinstance(hand, TwoFingerHand):
        return PaperRecord(hand)
    if isinstance(hand, ChainHand):
        return ChainRecord(hand)
    raise QsplanError(f"hand: expected a TwoFingerHand or a ChainHand; got {type(hand).__name__}")
