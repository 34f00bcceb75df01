"""Validation of estimator parameters against declared constraints.

Each estimator declares, in a class attribute ``_parameter_constraints``,
the values each constructor parameter may take: a dict from parameter name
to a list of constraints, the value being valid when it satisfies at least
one of them. ``fit``, decorated with :func:`validates_parameters`, checks
them before doing anything else, so a wrong value fails at once with a
message naming the parameter, the estimator and what is allowed, as
scikit-learn's own estimators do.

A constraint is one of

* an :class:`Interval` of integers or of real numbers;
* an :class:`Options`, a finite set of allowed values of one type
  (``Options(str, {"hold", "polynomial"})``);
* ``None``: the value ``None``;
* a class: any instance of it (``isinstance``; ``tuple``, ``Integral``,
  ``BLAEstimator``);
* one of the strings

  - ``"boolean"``: ``bool`` or ``numpy.bool_``;
  - ``"array-like"``: a list, tuple, array or other sized container of at
    least one dimension (not a string, a mapping, a set or a 0-d array);
  - ``"verbose"``: a bool or an int >= 0;
  - ``"random_state"``: ``None``, an int in ``[0, 2**32 - 1]`` or a
    ``numpy.random.RandomState`` (what ``check_random_state`` turns into a
    generator and tensorly accepts; not a ``numpy.random.Generator``).

Booleans are not numbers here: ``True`` is neither in an :class:`Interval`
nor in ``Options(int, {1})``. A plain class constraint, though, is
``isinstance`` and nothing more (``True`` is an instance of ``Integral``).

This module is the library's own: it replaces scikit-learn's private
parameter validation so that the library relies on public scikit-learn API
only. Unlike scikit-learn's, it does not switch off the validation of
estimators fitted inside a ``fit``: they check their own parameters again,
which costs microseconds.

Internal: not part of the API; may change without notice.

Examples
--------
>>> from numbers import Integral
>>> from sklearn.base import BaseEstimator
>>> from sklearn_pnlss.utils.parameters import Interval, Options, validates_parameters
>>> class Smoother(BaseEstimator):
...     _parameter_constraints = {
...         "window": [Interval(Integral, 1, None, closed="left")],
...         "mode": [Options(str, {"mean", "median"}), None],
...     }
...
...     def __init__(self, window=3, mode="mean"):
...         self.window = window
...         self.mode = mode
...
...     @validates_parameters
...     def fit(self, X, y=None):
...         return self
>>> Smoother(window=5).fit([[0.0]]).window
5
>>> Smoother(window=0).fit([[0.0]])
Traceback (most recent call last):
    ...
sklearn_pnlss.utils.parameters.InvalidParameterError: The 'window' parameter of Smoother must be an int in the range [1, inf). Got 0 instead.
>>> Smoother(mode="max").fit([[0.0]])
Traceback (most recent call last):
    ...
sklearn_pnlss.utils.parameters.InvalidParameterError: The 'mode' parameter of Smoother must be a str among {'mean', 'median'} or None. Got 'max' instead.
"""
import functools
import math
from collections.abc import Mapping, Set
from numbers import Integral, Real

import numpy as np

__all__ = [
    "InvalidParameterError",
    "Interval",
    "Options",
    "check_parameter",
    "validate_parameters",
    "validates_parameters",
]

_MAX_SEED = 2**32 - 1
_CLOSED = ("left", "right", "both", "neither")
_MAX_REPR = 100  # characters of the rejected value shown in a message
_class = type  # Interval and Options take a parameter named ``type``


class InvalidParameterError(ValueError, TypeError):
    """A parameter has a value its constraints do not allow.

    Both a :class:`ValueError` and a :class:`TypeError`, whichever the
    mistake is, as scikit-learn's estimator checks and users' ``except``
    clauses expect.

    Examples
    --------
    >>> from sklearn_pnlss.utils.parameters import InvalidParameterError
    >>> issubclass(InvalidParameterError, ValueError), issubclass(InvalidParameterError, TypeError)
    (True, True)
    """


def _is_bool(value):
    return isinstance(value, (bool, np.bool_))


def _article(words):
    return ("an " if words[:1].lower() in ("a", "e", "i", "o", "u") else "a ") + words


class _Constraint:
    """One allowed kind of value: :meth:`accepts` and a description that
    completes "must be ..."."""

    def accepts(self, value):
        raise NotImplementedError

    def description(self):
        raise NotImplementedError

    def __str__(self):
        return self.description()


class Interval(_Constraint):
    """Integers or real numbers between two bounds.

    Parameters
    ----------
    type : {numbers.Integral, numbers.Real}
        ``Integral``: ints, numpy integers included. ``Real``: any real
        number, ints included, NaN excluded (described as "a float", the
        word scikit-learn's messages use). Booleans are neither.
    left, right : int, float or None
        The bounds; None is an infinite bound (-inf on the left, +inf on
        the right). With ``Integral`` they must be ints (or None).
    closed : {"left", "right", "both", "neither"}, default="neither"
        Which bounds belong to the interval. An infinite bound belongs to
        it only when its side is closed: ``Interval(Real, 0, None,
        closed="left")`` is ``[0, inf)`` and rejects ``inf``;
        ``closed="both"`` makes it ``[0, inf]``.

    Examples
    --------
    >>> from numbers import Integral, Real
    >>> from sklearn_pnlss.utils.parameters import Interval
    >>> degree = Interval(Integral, 2, None, closed="left")
    >>> print(degree)
    an int in the range [2, inf)
    >>> degree.accepts(2), degree.accepts(1), degree.accepts(2.0), degree.accepts(True)
    (True, False, False, False)
    >>> Interval(Real, 0, 1, closed="neither").accepts(0.5)
    True
    """

    def __init__(self, type, left, right, *, closed="neither"):
        if type not in (Integral, Real):
            raise ValueError(f"Interval type must be numbers.Integral or numbers.Real; got {type!r}.")
        if closed not in _CLOSED:
            raise ValueError(f"Interval closed must be one of {_CLOSED}; got {closed!r}.")
        for side, bound in (("left", left), ("right", right)):
            if bound is None:
                continue
            if _is_bool(bound) or not isinstance(bound, Real) or math.isnan(bound):
                raise TypeError(f"Interval {side} bound must be a number or None; got {bound!r}.")
            if type is Integral and not isinstance(bound, Integral) and not math.isinf(bound):
                raise TypeError(
                    f"an Interval of integers needs int bounds (or None); got {side}={bound!r}."
                )
        self.type = type
        self.left = None if left is not None and left == -math.inf else left
        self.right = None if right is not None and right == math.inf else right
        self.closed = closed
        lo, hi = self._low(), self._high()
        if lo > hi or (lo == hi and closed != "both"):
            raise ValueError(f"Interval {self._notation()} is empty.")

    def _low(self):
        return -math.inf if self.left is None else self.left

    def _high(self):
        return math.inf if self.right is None else self.right

    def _closed_left(self):
        return self.closed in ("left", "both")

    def _closed_right(self):
        return self.closed in ("right", "both")

    def accepts(self, value):
        """Whether ``value`` is a number of the right type inside the interval.

        Parameters
        ----------
        value : object

        Returns
        -------
        bool
        """
        if _is_bool(value) or not isinstance(value, self.type):
            return False
        if math.isnan(value):
            return False
        lo, hi = self._low(), self._high()
        if value < lo or (value == lo and not self._closed_left()):
            return False
        if value > hi or (value == hi and not self._closed_right()):
            return False
        return True

    def _notation(self):
        lo = "-inf" if self.left is None else str(self.left)
        hi = "inf" if self.right is None else str(self.right)
        return f"{'[' if self._closed_left() else '('}{lo}, {hi}{']' if self._closed_right() else ')'}"

    def description(self):
        """What the interval allows, as in "must be an int in the range [2, inf)".

        Returns
        -------
        str
        """
        kind = "an int" if self.type is Integral else "a float"
        return f"{kind} in the range {self._notation()}"

    def __repr__(self):
        return (f"Interval({self.type.__name__}, {self.left!r}, {self.right!r}, "
                f"closed={self.closed!r})")


class Options(_Constraint):
    """A finite set of allowed values of one type.

    Parameters
    ----------
    type : type
        The type every value must have (``str`` for string options).
        Booleans are not accepted unless ``type`` is ``bool``.
    options : iterable
        The allowed values, all instances of ``type``.

    Examples
    --------
    >>> from sklearn_pnlss.utils.parameters import Options
    >>> extrapolation = Options(str, {"hold", "polynomial"})
    >>> print(extrapolation)
    a str among {'hold', 'polynomial'}
    >>> extrapolation.accepts("hold"), extrapolation.accepts("linear"), extrapolation.accepts(["hold"])
    (True, False, False)
    """

    def __init__(self, type, options):
        if not isinstance(type, _class):
            raise TypeError(f"Options type must be a class; got {type!r}.")
        if isinstance(options, (str, bytes)):
            raise TypeError(f"Options needs a collection of options, not the single value {options!r}.")
        options = frozenset(options)
        if not options:
            raise ValueError("Options needs at least one option.")
        wrong = [o for o in options if not isinstance(o, type)]
        if wrong:
            raise TypeError(f"Options of type {type.__name__} given {sorted(map(repr, wrong))}.")
        self.type = type
        self.options = options

    def accepts(self, value):
        """Whether ``value`` has the type and is one of the options.

        Parameters
        ----------
        value : object

        Returns
        -------
        bool
        """
        if not isinstance(value, self.type):
            return False
        if _is_bool(value) and not issubclass(self.type, (bool, np.bool_)):
            return False
        try:
            return value in self.options
        except TypeError:  # unhashable instance of a user type
            return False

    def description(self):
        """What the options allow, as in "must be a str among {'a', 'b'}".

        Returns
        -------
        str
        """
        listed = ", ".join(sorted(map(repr, self.options)))
        return f"{_InstanceOf(self.type).description()} among {{{listed}}}"

    def __repr__(self):
        return f"Options({self.type.__name__}, {{{', '.join(sorted(map(repr, self.options)))}}})"


class _NoneConstraint(_Constraint):
    def accepts(self, value):
        return value is None

    def description(self):
        return "None"


class _InstanceOf(_Constraint):
    _NAMES = {Integral: "an int", Real: "a float"}

    def __init__(self, cls):
        self.cls = cls

    def accepts(self, value):
        return isinstance(value, self.cls)

    def description(self):
        if self.cls in self._NAMES:
            return self._NAMES[self.cls]
        if self.cls.__module__ == "builtins":
            return _article(self.cls.__name__)
        return f"an instance of {self.cls.__qualname__}"


class _Boolean(_Constraint):
    def accepts(self, value):
        return _is_bool(value)

    def description(self):
        return "a bool"


class _ArrayLike(_Constraint):
    def accepts(self, value):
        if isinstance(value, (str, bytes, Mapping, Set)):
            return False
        shape = getattr(value, "shape", None)
        if shape is not None:  # arrays, data frames: at least one dimension
            try:
                return len(shape) > 0
            except TypeError:
                return False
        return hasattr(value, "__len__") or hasattr(value, "__array__")

    def description(self):
        return "an array-like (list, tuple or array)"


class _Verbose(_Constraint):
    _COUNT = Interval(Integral, 0, None, closed="left")

    def accepts(self, value):
        return _is_bool(value) or self._COUNT.accepts(value)

    def description(self):
        return f"a bool or {self._COUNT.description()}"


class _RandomState(_Constraint):
    _SEED = Interval(Integral, 0, _MAX_SEED, closed="both")

    def accepts(self, value):
        return value is None or self._SEED.accepts(value) or isinstance(value, np.random.RandomState)

    def description(self):
        return f"None, {self._SEED.description()} or an instance of numpy.random.RandomState"


_NAMED = {
    "boolean": _Boolean(),
    "array-like": _ArrayLike(),
    "verbose": _Verbose(),
    "random_state": _RandomState(),
}


def _as_constraint(constraint):
    """The constraint object for one entry of a constraints list."""
    if isinstance(constraint, _Constraint):
        return constraint
    if constraint is None:
        return _NoneConstraint()
    if isinstance(constraint, str):
        try:
            return _NAMED[constraint]
        except KeyError:
            raise ValueError(
                f"unknown constraint {constraint!r}; the named constraints are {sorted(_NAMED)}."
            ) from None
    if isinstance(constraint, _class):
        return _InstanceOf(constraint)
    raise TypeError(
        f"unknown constraint {constraint!r}: use an Interval, an Options, None, a class "
        f"or one of {sorted(_NAMED)}."
    )


def _shown(value):
    text = repr(value)
    return text if len(text) <= _MAX_REPR else text[: _MAX_REPR - 3] + "..."


def check_parameter(value, constraints, *, name, owner):
    """Check one parameter value against its list of constraints.

    Parameters
    ----------
    value : object
        The value to check.
    constraints : list
        Allowed kinds of value (see the module docstring); the value is
        valid when it satisfies at least one.
    name : str
        Parameter name, for the message.
    owner : str
        Who the parameter belongs to (an estimator class name, a function),
        for the message.

    Raises
    ------
    InvalidParameterError
        When no constraint accepts ``value``.
    ValueError or TypeError
        When ``constraints`` is not a list of known constraints (a mistake
        in the code, not in the user's value).

    Examples
    --------
    >>> from numbers import Real
    >>> from sklearn_pnlss.utils.parameters import Interval, check_parameter
    >>> check_parameter(0.5, [Interval(Real, 0, 1, closed="neither")], name="alpha", owner="f")
    >>> check_parameter(1.0, [Interval(Real, 0, 1, closed="neither")], name="alpha", owner="f")
    Traceback (most recent call last):
        ...
    sklearn_pnlss.utils.parameters.InvalidParameterError: The 'alpha' parameter of f must be a float in the range (0, 1). Got 1.0 instead.
    """
    if not isinstance(constraints, (list, tuple)) or not constraints:
        raise TypeError(
            f"the constraints of {owner}'s {name!r} must be a non-empty list; got {constraints!r}."
        )
    constraints = [_as_constraint(c) for c in constraints]
    if any(c.accepts(value) for c in constraints):
        return
    # None reads best last: "an int in the range [2, inf) or None".
    constraints.sort(key=lambda c: isinstance(c, _NoneConstraint))
    allowed = [c.description() for c in constraints]
    allowed = allowed[0] if len(allowed) == 1 else f"{', '.join(allowed[:-1])} or {allowed[-1]}"
    raise InvalidParameterError(
        f"The {name!r} parameter of {owner} must be {allowed}. Got {_shown(value)} instead."
    )


def validate_parameters(estimator):
    """Check an estimator's parameters against its class's constraints.

    Every parameter of ``estimator.get_params(deep=False)`` named in
    ``type(estimator)._parameter_constraints`` is checked; a parameter the
    dict does not name is not.

    Parameters
    ----------
    estimator : estimator instance
        Has ``get_params`` and a class attribute ``_parameter_constraints``
        (dict: parameter name -> list of constraints).

    Raises
    ------
    InvalidParameterError
        At the first parameter whose value no constraint accepts.

    Examples
    --------
    >>> from sklearn_pnlss import BLAEstimator
    >>> from sklearn_pnlss.utils.parameters import validate_parameters
    >>> validate_parameters(BLAEstimator(n_states=2))
    >>> validate_parameters(BLAEstimator(refine="yes"))
    Traceback (most recent call last):
        ...
    sklearn_pnlss.utils.parameters.InvalidParameterError: The 'refine' parameter of BLAEstimator must be a bool. Got 'yes' instead.
    """
    cls = type(estimator)
    constraints = getattr(cls, "_parameter_constraints", None)
    if not isinstance(constraints, Mapping):
        raise TypeError(
            f"{cls.__name__} declares no _parameter_constraints dict to validate its parameters against."
        )
    for name, value in estimator.get_params(deep=False).items():
        if name in constraints:
            check_parameter(value, constraints[name], name=name, owner=cls.__name__)


def validates_parameters(fit):
    """Decorate ``fit`` to validate the estimator's parameters first.

    The wrapped method calls :func:`validate_parameters` on ``self``, then
    runs ``fit`` unchanged (same signature, docstring and return value).

    Parameters
    ----------
    fit : callable
        A method whose first argument is the estimator.

    Returns
    -------
    callable
        The decorated method.

    Examples
    --------
    >>> from sklearn.base import BaseEstimator
    >>> from sklearn_pnlss.utils.parameters import validates_parameters
    >>> class Echo(BaseEstimator):
    ...     _parameter_constraints = {"copy": ["boolean"]}
    ...
    ...     def __init__(self, copy=True):
    ...         self.copy = copy
    ...
    ...     @validates_parameters
    ...     def fit(self, X, y=None):
    ...         return self
    >>> Echo(copy=1).fit(None)
    Traceback (most recent call last):
        ...
    sklearn_pnlss.utils.parameters.InvalidParameterError: The 'copy' parameter of Echo must be a bool. Got 1 instead.
    """

    @functools.wraps(fit)
    def wrapper(self, *args, **kwargs):
        validate_parameters(self)
        return fit(self, *args, **kwargs)

    return wrapper
