"""The instructor kit: lecture slides, exercise solutions, a static course page and an nbgrader course, all made
from the lessons themselves (``make slides``, ``posekit exercises solutions LESSON``, ``make course``,
``posekit course nbgrader``)."""
