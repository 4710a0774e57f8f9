"""Reference solutions of the lessons' checked exercises, one module per lesson (``nb00`` ... ``nb06``).

The instructor's version: every function is self-contained (its imports inside its body), so that
``posekit exercises solutions NN`` can paste its source in place of the notebook's stub. Each one passes
its checker in :mod:`posekit.exercises`.
"""
