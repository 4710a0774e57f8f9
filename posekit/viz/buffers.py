"""pythreejs buffers that cost no messages the page need not send: a ``BufferAttribute`` whose version the browser
never reports back (:func:`attribute`) and a ``BufferGeometry`` with the empty morph-target list three.js makes
(:func:`geometry`).

Introduced with :class:`~posekit.viz.SkeletonViewer` (``notebooks/00_skeletons_and_poses.ipynb``): the viewer's meshes
(:mod:`posekit.viz.meshes`) are made of them, and the shared constant buffers (:mod:`posekit.viz.shared`) are one
such model for every view of a page. Both of those import this module; it imports neither.
"""

from __future__ import annotations

__all__ = ["FIRST_VERSION", "attribute", "geometry"]

_ATTRIBUTE = None

FIRST_VERSION = 1
"""The ``version`` the browser's copy of a new pythreejs ``BufferAttribute`` starts at: three.js counts 1 when it
first takes the array. pythreejs's own default is -1, so the browser reported the 1 back as a page opened, one
message for every attribute of every view (about 130 for the studio's four views, each handled by the kernel,
each answered with a busy/idle pair). An attribute made with the browser's number has nothing to report."""


def attribute(array):
    """A pythreejs ``BufferAttribute`` of ``array`` that costs no messages the kernel does not need.

    Every time the kernel sends a new array, the browser's copy of the attribute counts its ``version`` up and
    reports it to the kernel, and ipywidgets 8 answers each report with an echo of the same number: two
    messages and a busy/idle pair per array per update, for a number the kernel never reads or sets. This
    attribute (the same model in the browser) is not echoed, so a live update costs fewer messages; and it
    starts at :data:`FIRST_VERSION`, so a page that opens sends nothing back for it."""
    global _ATTRIBUTE
    if _ATTRIBUTE is None:
        import pythreejs as three
        from traitlets import CInt

        class Attribute(three.BufferAttribute):
            version = CInt(-1, allow_none=False).tag(sync=True, echo_update=False)

        _ATTRIBUTE = Attribute
    return _ATTRIBUTE(array, normalized=False, version=FIRST_VERSION)


def geometry(attributes: dict):
    """A pythreejs ``BufferGeometry`` of ``attributes`` (name -> :func:`attribute`) with an empty list of morph
    targets: a three.js mesh made on a geometry without one has no morph weights, where its pythreejs model holds
    an empty list, so every mesh reported an empty list back to the kernel as a page opened (28 messages for the
    studio's four views). Nothing is morphed: the list stays empty."""
    import pythreejs as three

    return three.BufferGeometry(attributes=attributes, morphAttributes={"position": []})
