"""A course's view: a submission's parts (a controller, a planner, a trajectory class, in
plain Python) graded on the course's maps and seeds, with the report a TA hands back
(``quadnav grade``; docs/grading.md).

:class:`~quadnav.grading.course.Course` is what the course grades (:func:`read_course`
reads the TA's ``grade.toml``); :class:`~quadnav.grading.run.Grade` flies every mission
with the submission's parts and with quadnav's own, each through the library's one
mission path into a run folder, and writes ``grade.json``, ``grade.csv`` and
``grade.html`` (:mod:`quadnav.grading.report`).
"""

from quadnav.grading.course import Course, read_course
from quadnav.grading.run import Grade

__all__ = ["Course", "Grade", "read_course"]
