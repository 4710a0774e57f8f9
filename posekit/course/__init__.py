"""The instructor kit: lecture slides, exercise solutions and a static course page, all made from the
lessons themselves (``make slides``, ``posekit exercises solutions LESSON``, ``make course``)."""
