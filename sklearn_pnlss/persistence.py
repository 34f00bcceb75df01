"""Saving fitted models to disk and loading them back, with joblib.

A file holds two joblib records one after the other: a small header (what
wrote it: the library version and the file-format version), then the model.
:func:`load` reads the header first and refuses a file written by an
incompatible version *before* unpickling the model, since unpickling
classes that have changed fails in obscure ways, or worse, silently gives a
model that predicts differently.

Like every pickle-based format, a file can run code when loaded: load only
files you trust.
"""
import warnings
from pathlib import Path

import joblib

from . import __version__

__all__ = ["FORMAT_VERSION", "IncompatibleModelFileError", "load", "read_header", "save"]

#: Version of the file layout and of the pickled estimators' attributes;
#: raised whenever a file written before cannot be read correctly any more
#: (2: the fitted model is the public ``model_``, a ScaledModel).
FORMAT_VERSION = 2

_MAGIC = "sklearn_pnlss model file"


class IncompatibleModelFileError(ValueError):
    """The file was written by a version of sklearn_pnlss this one cannot
    read (or is not a sklearn_pnlss model file)."""


def _release(version):
    """``(major, minor)`` of a version string; pickled estimators are only
    compatible within one release series."""
    parts = str(version).split(".")
    return tuple(parts[:2])


def _header():
    import sklearn

    return {
        "magic": _MAGIC,
        "format_version": FORMAT_VERSION,
        "library_version": __version__,
        "sklearn_version": sklearn.__version__,
    }


def save(model, path, *, compress=3):
    """Write a (fitted) estimator or Pipeline to ``path`` with joblib.

    Parameters
    ----------
    model : object
        Typically a fitted estimator of the library or a Pipeline of them.
    path : str or path-like
        File to write (conventionally ``*.joblib``); overwritten if present.
    compress : int from 0 to 9, default=3
        zlib compression level of the model record (0: none).

    Returns
    -------
    path : pathlib.Path

    See Also
    --------
    load : read the file back.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from sklearn_pnlss import PNLSSRegressor
    >>> from sklearn_pnlss.persistence import load, save
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = save(PNLSSRegressor(degrees=(2, 3)), pathlib.Path(folder) / "model.joblib")
    ...     load(path).degrees
    (2, 3)
    """
    path = Path(path)
    with open(path, "wb") as fh:
        # The header stays uncompressed: load reads it record by record
        # from the same file object, and a decompressor may read ahead.
        joblib.dump(_header(), fh)
        joblib.dump(model, fh, compress=compress)
    return path


def read_header(path):
    """The header of a model file: ``format_version``, ``library_version``
    and ``sklearn_version`` of the writer.

    Raises
    ------
    IncompatibleModelFileError
        If ``path`` is not a file written by :func:`save`.
    """
    with open(path, "rb") as fh:
        return _read_header(fh, path)


def _read_header(fh, path):
    try:
        header = joblib.load(fh)
    except Exception:  # any unreadable start: not one of our files
        header = None
    if not (isinstance(header, dict) and header.get("magic") == _MAGIC):
        raise IncompatibleModelFileError(
            f"{str(path)!r} is not a model file written by sklearn_pnlss.persistence.save; "
            "a plain joblib or pickle file is read with joblib.load instead."
        )
    return header


def load(path):
    """Read a model written by :func:`save`.

    The file must come from the same file-format version and the same
    sklearn_pnlss release series (``major.minor``) as the installed library;
    otherwise it is refused before the model is unpickled. A different
    scikit-learn version only warns (scikit-learn itself warns too).

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    model : the saved object

    Raises
    ------
    IncompatibleModelFileError
        If the file is not a model file of this library, or was written by
        an incompatible version; the message names both versions and what to
        do.

    See Also
    --------
    save

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from sklearn_pnlss import BLAEstimator
    >>> from sklearn_pnlss.persistence import load, read_header, save
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = save(BLAEstimator(n_states=2), pathlib.Path(folder) / "bla.joblib")
    ...     read_header(path)["format_version"], load(path).n_states
    (2, 2)
    """
    with open(path, "rb") as fh:
        header = _read_header(fh, path)
        written, fmt = header.get("library_version"), header.get("format_version")
        if fmt != FORMAT_VERSION or _release(written) != _release(__version__):
            raise IncompatibleModelFileError(
                f"{str(path)!r} was written by sklearn_pnlss {written} (model file format {fmt}); "
                f"this is sklearn_pnlss {__version__} (file format {FORMAT_VERSION}), which cannot "
                f"read it. Load it with sklearn_pnlss {'.'.join(_release(written))}.x "
                f"(pip install 'sklearn_pnlss=={'.'.join(_release(written))}.*'), or fit the model "
                "again with this version and save it anew."
            )
        import sklearn

        if header.get("sklearn_version") != sklearn.__version__:
            warnings.warn(
                f"{str(path)!r} was written with scikit-learn {header.get('sklearn_version')}; "
                f"this is scikit-learn {sklearn.__version__}. Check the model's predictions, or "
                "install the version it was written with.",
                UserWarning,
                stacklevel=2,
            )
        return joblib.load(fh)
