"""Geometry of a hand and workpiece: the workpiece polygon, overlaps and collisions between the bodies.

* :mod:`.workpiece` - the workpiece: a convex polygon resting on one edge on the palm
* :mod:`.overlap` - overlap of convex polygons in numpy, batched
* :mod:`.collision_view` - a hand as the collision test sees it: its bodies, the joint housings
* :mod:`.collision` - collisions between every pair of palm, links and workpiece
"""
