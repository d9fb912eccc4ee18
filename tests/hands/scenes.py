"""One comparison of two scenes of the hand, shared by the tests of the analytic scenes and of the grasps."""

import numpy as np

#: The scene fields compared.
FIELDS = ("Wn", "Wt", "Jn", "Jt", "mu", "g_obj", "g_man", "joint_velocity", "joint_effort")
RTOL = 1e-12  # round-off: the two paths compute the same products in a different order at most


def assert_same_scene(a, g):
    """An analytic scene ``a`` equals the generic one ``g`` to round-off (names, control modes, every field)."""
    assert a.contact_names == g.contact_names and a.joint_names == g.joint_names
    assert a.virtual_joints == g.virtual_joints
    np.testing.assert_array_equal(a.effort_controlled, g.effort_controlled)
    for f in FIELDS:
        A, G = getattr(a, f), getattr(g, f)
        assert A.shape == G.shape, f
        np.testing.assert_array_equal(np.isnan(A), np.isnan(G), err_msg=f)
        scale = max(float(np.nanmax(np.abs(G), initial=0.0)), 1e-300)
        np.testing.assert_allclose(A, G, rtol=RTOL, atol=RTOL * scale, err_msg=f)
