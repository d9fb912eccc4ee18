"""Serial-chain hands: two fingers of revolute and prismatic joints on a palm (Section 3, eqs. 1-5).

* :mod:`.hand` - the chain hand record holding a workpiece (its polygons, contacts, scenes)
* :mod:`.record` - that record answering for itself from its description (:class:`~qsplan.hands.protocol.HandRecord`)
* :mod:`.closing` - closing one finger onto the workpiece: where its last joint first touches
* :mod:`.closing_batch` - the same closing at many states at once
* :mod:`.arrays` - the model's matrices of a described hand's grasps at many states at once
* :mod:`.reclose` - the fingers closed again on a workpiece that moved (a plan's grasp at another pose)
"""
