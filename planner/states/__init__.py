"""Judging configurations: in contact (the contacts kept, limits, no overlap, the desired mode's kinematics and a
guaranteed band) and in free space (limits, no overlap).

* :mod:`.contact` - :func:`~.contact.check_contact_state`, :func:`~.contact.check_free_state`, the judged
  :class:`~.contact.StateCheck`
* :mod:`.grasped` - samples and scenes of a named grasp along the palm
* :mod:`.collision` - overlap between every pair of a hand's bodies; :mod:`.collision_view` the hand as the
  test sees it; :mod:`.overlap` convex-polygon overlap in numpy, batched
"""
