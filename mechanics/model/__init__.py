"""The model of one instant (Section 3): frames, wrenches, the manipulator, scenes and their files.

* :mod:`.contact` - contact frames and wrench matrices ``W_n, W_t`` (eq. 1)
* :mod:`.manipulator` - planar kinematic trees: link poses, Jacobians ``J_n, J_t`` (eq. 5), gravity efforts (eq. 3)
* :mod:`.scene` - the frozen :class:`Scene` of one instant (eqs. 1-11's data), ``check_finite_array``
* :mod:`.geometry` - contacts found from polygons (eq. 1's points and normals)
* :mod:`.geometric_scene` - polygons and a joint tree in, a scene out (eqs. 1-5)
* :mod:`.scene_io`, :mod:`.scene_io_write` - the raw form read and written (TOML/JSON)
* :mod:`.fields` - validators of document fields; :mod:`.friction` - the one friction validator (eq. 8)
"""
