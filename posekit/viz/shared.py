"""Widget models that every view of a page shares: one ``Layout`` per distinct layout, one ``Style`` per widget kind
and style, one pythreejs material per kind of surface, one buffer per distinct constant array.

Introduced with :class:`~posekit.viz.SkeletonViewer` (``notebooks/00_skeletons_and_poses.ipynb``); the posing studio
(``notebooks/06_posing_studio.ipynb``) is made of them. Left to itself, every ipywidgets widget makes a ``Layout``
model and a ``Style`` model of its own, and every view its own materials and index buffers: the studio's default page
held 653 models, 155 of them ``Layout``s, and a page that opens receives and builds each one before it shows. A
shared model is the same model for every widget that asks for the same traits, so the page builds it once.

A shared model is never changed after it is made (changing it would change every widget that holds it): a widget
whose layout changes at run time (a part shown or hidden) keeps a ``Layout`` of its own. A shared model that was
closed (``ipywidgets.Widget.close_all()``) is made anew the next time it is asked for.
"""

from __future__ import annotations

import hashlib

import numpy as np

from .buffers import attribute, geometry

__all__ = ["layout", "widget", "model", "material", "constant_attribute", "constant_geometry", "release"]

_MODELS = {}
_HOLDERS = {}  # constant attributes: key -> how many holders asked for the model and have not released it


def _shared(key, make):
    model = _MODELS.get(key)
    if model is None or model.comm is None:  # never made, or closed since
        model = _MODELS[key] = make()
        _HOLDERS.pop(key, None)
    return model


def _key(traits: dict) -> tuple:
    return tuple(sorted((k, tuple(v) if isinstance(v, list) else v) for k, v in traits.items()))


def _layout(traits: dict):
    import ipywidgets as w

    return _shared(("Layout", _key(traits)), lambda: w.Layout(**traits))


def layout(**traits):
    """The shared ``ipywidgets.Layout`` with these traits (e.g. ``width="110px"``; none: the default layout)."""
    return _layout(traits)


def widget(cls, *args, layout: dict | None = None, style: dict | None = None, **traits):
    """``cls(*args, **traits)`` (an ipywidgets class) with a shared :func:`layout` of the traits ``layout`` and, when
    the class has a style, a shared style of the traits ``style`` — in place of a new Layout and Style model each.

    Parameters
    ----------
    cls : type
        An ``ipywidgets.DOMWidget`` subclass (``ipywidgets.Button``, ``ipywidgets.VBox`` ...).
    layout : dict or ipywidgets.Layout, optional
        Layout traits (``{"width": "230px"}``) of a shared layout, or a Layout of the widget's own (one that will
        change: ``ipywidgets.Layout(display="none")`` for a part shown later).
    style : dict, optional
        Style traits (``{"button_width": "70px"}``).
    """
    import ipywidgets as w

    traits["layout"] = layout if isinstance(layout, w.Layout) else _layout(dict(layout or {}))
    kind = cls.class_traits().get("style")
    if kind is not None:
        style_cls, style = kind.klass, dict(style or {})
        traits["style"] = _shared((style_cls.__name__, _key(style)), lambda: style_cls(**style))
    elif style:
        raise ValueError(f"{cls.__name__} has no style to give {style!r}")
    return cls(*args, **traits)


def model(cls, **traits):
    """The shared model ``cls(**traits)`` (a pythreejs class no view changes: a material, a light's shadow, a
    renderer's shadow map); traits given by name."""
    return _shared((cls.__name__, _key(traits)), lambda: cls(**traits))


def material(cls, **traits):
    """The shared pythreejs material ``cls(**traits)`` (e.g. ``pythreejs.MeshLambertMaterial``,
    ``vertexColors="VertexColors"``): every view's meshes of one kind hold the same material model."""
    return model(cls, **traits)


def constant_attribute(array):
    """The shared :func:`~posekit.viz.buffers.attribute` of ``array``'s values (a buffer no one changes: triangle
    indices, the colours of a ghost), one model for every geometry that holds the same values. Each call counts one
    holder more; a holder that lets the model go calls :func:`release`."""
    array = np.ascontiguousarray(array)
    key = ("attribute", array.dtype.str, array.shape, hashlib.sha1(array.tobytes()).hexdigest())
    model = _shared(key, lambda: attribute(array))
    _HOLDERS[key] = _HOLDERS.get(key, 0) + 1
    return model


def release(model) -> None:
    """One holder of a :func:`constant_attribute` lets it go: the model is closed when no holder is left (a model
    made otherwise is closed at once)."""
    key = next((k for k, m in _MODELS.items() if m is model and k in _HOLDERS), None)
    if key is None:
        model.close()
        return
    _HOLDERS[key] -= 1
    if _HOLDERS[key] <= 0:
        del _HOLDERS[key], _MODELS[key]
        model.close()


def constant_geometry(attributes: dict):
    """The shared :func:`~posekit.viz.buffers.geometry` of ``attributes`` (name -> :func:`constant_attribute`): one
    model for every mesh of a shape no one changes (the invisible sphere that mouse rays meet, in every view)."""
    key = ("geometry", tuple(sorted((name, a.model_id) for name, a in attributes.items())))
    return _shared(key, lambda: geometry(attributes))
