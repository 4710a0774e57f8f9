"""nbgrader's ``collect`` that refuses, rather than warns about, a submission made in another student's name.

On a shared machine every student submits into one exchange folder, and a submission's name says whose it is
(``<student id>+<assignment>+<time>+<random>``). Anyone can put any id there: ``nbgrader submit ps1
--student=bob`` run by alice makes a submission named bob's, owned by alice's system user. nbgrader's own
``collect`` sees the mismatch but only logs a warning ("cheating attempt?") and, when the forged one is the newest,
collects it *in place of* bob's real submission. :class:`OwnerCheckedCollect` (the course's ``nbgrader_config.py``
names it, :mod:`posekit.course.nbgrader`):

* keeps, for each student, the newest submission that student's own system user made, and refuses every other one,
  naming it, its owner and the student it claims to be (``refused`` holds them after a run);
* refuses a submission that holds a link (the instructor's copy would follow it, as root or as themselves, to a
  file the student could not read);
* names a student as the hub does: a system user made by the class hub (``posekit-<name>``) carries the hub name in
  its comment field ("posekit hub user bob"), and that is the name a submission must carry
  (deploy/jupyterhub/posekit_spawner.py); any other system user is its own name.
"""

from __future__ import annotations

import os
import pwd

from nbgrader.exchange.default.collect import ExchangeCollect

__all__ = ["OwnerCheckedCollect", "student_of_uid", "HUB_USER_COMMENT"]

HUB_USER_COMMENT = "posekit hub user "
"""The start of a class hub student's system user's comment field, followed by their hub name."""


def student_of_uid(uid: int) -> str | None:
    """The student id a file owned by ``uid`` may carry: the hub name of a class hub's student, else the system
    user's name; None for a uid with no user."""
    try:
        pw = pwd.getpwuid(uid)
    except KeyError:
        return None
    return pw.pw_gecos[len(HUB_USER_COMMENT):] if pw.pw_gecos.startswith(HUB_USER_COMMENT) else pw.pw_name


def _has_link(path: str) -> bool:
    for dirpath, dirnames, filenames in os.walk(path):
        for name in dirnames + filenames:
            if os.path.islink(os.path.join(dirpath, name)):
                return True
    return False


class OwnerCheckedCollect(ExchangeCollect):
    """nbgrader's ``collect``, each student's submission chosen among those their own user made (module doc)."""

    def _refusal(self, record) -> str | None:
        """Why the submission of ``record`` (nbgrader's: ``username``, ``filename``) is refused, or None."""
        path = os.path.join(self.inbound_path, record["filename"])
        try:
            st = os.lstat(path)
        except OSError as err:
            return f"cannot be read ({err.strerror})"
        if os.path.islink(path) or not os.path.isdir(path):
            return "is not a folder"
        owner = student_of_uid(st.st_uid)
        if owner != record["username"]:
            return f"claims to be {record['username']}'s but was made by {owner or 'uid %d' % st.st_uid}"
        if _has_link(path):
            return "holds a link"
        return None

    def init_src(self):
        super().init_src()
        self.refused = []
        kept = []
        for chosen in self.src_records:
            if self._refusal(chosen) is None:
                kept.append(chosen)
                continue
            # the student's own submissions, newest first (the before-the-due-date choice as nbgrader makes it)
            pattern_records = [self._path_to_record(os.path.join(self.inbound_path, f))
                               for f in os.listdir(self.inbound_path)
                               if f.startswith(f"{chosen['username']}+{self.coursedir.assignment_id}+")]
            own = []
            for record in self._sort_by_timestamp(pattern_records):
                why = self._refusal(record)
                if why is None:
                    own.append(record)
                else:
                    self.refused.append((record["filename"], why))
                    self.log.error("Refused %s: it %s", record["filename"], why)
            if own and getattr(self, "duedate", None) is not None and self.before_duedate:
                on_time = [r for r in own if r["timestamp"] <= self.duedate]
                own = on_time or own
            if own:
                kept.append(own[0])
        self.src_records = kept
