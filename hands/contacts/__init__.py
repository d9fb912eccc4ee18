"""Contacts of a hand and workpiece as scenes (issue 23; Section 3, eqs. 1-5).

* :mod:`.found` - every contact the polygons show at a configuration, in one canonical order
* :mod:`.sets` - a scene from an explicit, named contact set at any workpiece pose
* :mod:`.point_scene` - the mechanics' matrices of contacts given by their points, normals and links
"""
