"""The paper hand of Fig. 9 in closed form (Section 5.2): the accelerator behind :class:`DescribedHand`.

* :mod:`.two_finger` - the palm and two single-link fingers holding a polygon (the hand record)
* :mod:`.record` - that record answering for itself (:class:`~qsplan.hands.protocol.HandRecord`), a described hand's
  answerer where the closed forms answer
* :mod:`.scene` - that hand's scene (geometric and raw) at a configuration
* :mod:`.analytic` - that scene at a grasp from the contacts the hand knows (the fast path)
* :mod:`.grasps` - where each finger touches (inner edge on a vertex, tip on an edge), in the user's numbering
* :mod:`.grasp_geometry` - a grasp's joint angles, contacts and rates along the palm (vectorized)
* :mod:`.batch_scenes` - a grasp's scenes at many positions at once
* :mod:`.accelerator` - the closed forms behind the :class:`~qsplan.hands.protocol.Hand` methods
* :mod:`.motion` - the paper hand's slides in closed form
* :mod:`.segments` - manipulation segments of that hand (segment 1: translate left in 4S)
"""
