"""The certifier (issues 12 and 21): every fact an exported plan states, checked from the task alone.

:mod:`.certify` (:func:`~.certify.certify_plan`) reads the files (:mod:`.inputs`) and runs the checks of
each row (:mod:`.rows`; the planned mode alone, :mod:`.modes`; the exported bands recomputed, :mod:`.bands`),
of the two files (:mod:`.files`) and of the whole motion (:mod:`.route`).
"""
