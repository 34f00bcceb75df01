"""The library's own parameter validation (sklearn_pnlss.utils.parameters):
each kind of constraint accepts and rejects the right values, messages name
the parameter, the estimator and what is allowed, and no module of the
library imports a private scikit-learn name."""
import ast
import importlib
import inspect
import math
import re
from fractions import Fraction
from numbers import Integral, Real
from pathlib import Path

import numpy as np
import pytest
from sklearn.base import BaseEstimator

import sklearn_pnlss
from sklearn_pnlss import BLAEstimator, DecoupledPNLSSRegressor, PNLSSRegressor
from sklearn_pnlss.utils.parameters import (
    Interval,
    InvalidParameterError,
    Options,
    check_parameter,
    validate_parameters,
    validates_parameters,
)

PACKAGE = Path(sklearn_pnlss.__file__).resolve().parent


def accepts(constraints, value):
    try:
        check_parameter(value, constraints, name="p", owner="Owner")
    except InvalidParameterError:
        return False
    return True


def message(constraints, value, name="p", owner="Owner"):
    with pytest.raises(InvalidParameterError) as info:
        check_parameter(value, constraints, name=name, owner=owner)
    return str(info.value)


# ---------------------------------------------------------------- Interval
@pytest.mark.parametrize("value", [2, 3, 10**30, np.int64(2), np.int8(5), np.uint64(7)])
def test_integer_interval_accepts_ints_of_any_kind(value):
    assert Interval(Integral, 2, None, closed="left").accepts(value)


@pytest.mark.parametrize(
    "value", [1, -5, 2.0, 2.5, True, np.True_, np.float64(3.0), "3", None, [3], Fraction(3), math.nan]
)
def test_integer_interval_rejects_the_rest(value):
    """Bools are not integers, floats are not integers even when whole."""
    assert not Interval(Integral, 2, None, closed="left").accepts(value)


def test_bool_is_not_a_number_even_inside_the_bounds():
    assert not Interval(Integral, 0, 1, closed="both").accepts(True)
    assert not Interval(Integral, 0, 1, closed="both").accepts(False)
    assert not Interval(Real, 0, 1, closed="both").accepts(np.False_)
    assert Interval(Integral, 0, 1, closed="both").accepts(1)


@pytest.mark.parametrize("value", [0.5, 1, np.float32(0.25), np.int64(1), Fraction(1, 3)])
def test_real_interval_accepts_ints_and_floats(value):
    assert Interval(Real, 0, 1, closed="right").accepts(value)


@pytest.mark.parametrize("value", [math.nan, np.nan, 1 + 0j, "0.5", None, np.array([0.5]), np.array(0.5)])
def test_real_interval_rejects_nan_and_non_numbers(value):
    assert not Interval(Real, None, None).accepts(value)


@pytest.mark.parametrize(
    "closed, expected",
    [
        ("both", {0: True, 0.5: True, 1: True}),
        ("left", {0: True, 0.5: True, 1: False}),
        ("right", {0: False, 0.5: True, 1: True}),
        ("neither", {0: False, 0.5: True, 1: False}),
    ],
)
def test_closed_ends(closed, expected):
    interval = Interval(Real, 0, 1, closed=closed)
    assert {v: interval.accepts(v) for v in expected} == expected
    assert not interval.accepts(-1e-12) and not interval.accepts(1 + 1e-12)


def test_infinite_bounds_follow_the_notation():
    """None is an infinite bound; an infinite end belongs to the interval
    only when its side is closed, as the printed range says."""
    half_line = Interval(Real, 0, None, closed="left")
    assert str(half_line) == "a float in the range [0, inf)"
    assert half_line.accepts(1e308) and not half_line.accepts(math.inf)
    assert Interval(Real, 0, None, closed="both").accepts(math.inf)
    assert str(Interval(Real, 0, None, closed="both")) == "a float in the range [0, inf]"
    below = Interval(Real, None, 0, closed="right")
    assert str(below) == "a float in the range (-inf, 0]"
    assert below.accepts(-1e308) and below.accepts(0) and not below.accepts(-math.inf)
    # an explicit infinite bound is the same as None
    assert str(Interval(Real, -math.inf, math.inf)) == "a float in the range (-inf, inf)"
    everything = Interval(Integral, None, None)
    assert everything.accepts(-(10**40)) and everything.accepts(10**40) and not everything.accepts(True)


@pytest.mark.parametrize(
    "args, kwargs, error, match",
    [
        ((float, 0, 1), {}, ValueError, "Integral or numbers.Real"),
        ((int, 0, 1), {}, ValueError, "Integral or numbers.Real"),
        ((Real, 0, 1), {"closed": "open"}, ValueError, "closed must be one of"),
        ((Real, 1, 0), {}, ValueError, "empty"),
        ((Real, 1, 1), {"closed": "left"}, ValueError, "empty"),
        ((Integral, 0.5, None), {}, TypeError, "int bounds"),
        ((Real, True, None), {}, TypeError, "left bound"),
        ((Real, 0, math.nan), {}, TypeError, "right bound"),
        ((Real, "0", None), {}, TypeError, "left bound"),
    ],
)
def test_interval_rejects_malformed_definitions(args, kwargs, error, match):
    with pytest.raises(error, match=match):
        Interval(*args, **kwargs)


def test_closed_is_keyword_only_and_a_point_interval_is_allowed():
    with pytest.raises(TypeError):
        Interval(Real, 0, 1, "left")
    point = Interval(Integral, 3, 3, closed="both")
    assert point.accepts(3) and not point.accepts(4)
    assert repr(point) == "Interval(Integral, 3, 3, closed='both')"


# ----------------------------------------------------------------- Options
def test_string_options():
    options = Options(str, {"hold", "polynomial"})
    assert options.accepts("hold") and options.accepts(np.str_("polynomial"))
    for value in ["linear", "Hold", "", None, 1, ["hold"], b"hold", {"hold": 1}]:
        assert not options.accepts(value), value
    assert str(options) == "a str among {'hold', 'polynomial'}"


def test_integer_options_refuse_bools_and_other_types():
    options = Options(Integral, {1, 2})
    assert options.accepts(1) and options.accepts(np.int64(2))
    assert not options.accepts(True) and not options.accepts(1.0) and not options.accepts(3)
    assert str(options) == "an int among {1, 2}"
    assert Options(bool, {True}).accepts(True)


def test_options_survive_unhashable_values():
    assert not Options(object, {"a"}).accepts(["a"])


@pytest.mark.parametrize(
    "args, error, match",
    [
        ((str, set()), ValueError, "at least one option"),
        ((str, "hold"), TypeError, "collection"),
        ((str, {"hold", 3}), TypeError, "Options of type str"),
        (("str", {"hold"}), TypeError, "must be a class"),
    ],
)
def test_options_reject_malformed_definitions(args, error, match):
    with pytest.raises(error, match=match):
        Options(*args)


# ------------------------------------------------------- named constraints
@pytest.mark.parametrize(
    "constraint, good, bad",
    [
        ("boolean", [True, False, np.True_, np.bool_(False)], [0, 1, "True", None, 1.0, [True]]),
        (
            "array-like",
            [[1, 2], (3,), [], np.zeros(3), np.zeros((2, 2)), range(3)],
            ["abc", b"ab", 3, 2.5, np.float64(1.0), np.array(2.0), {1: 2}, {1, 2}, None, iter([1])],
        ),
        ("verbose", [0, 3, np.int64(2), True, False, np.True_], [-1, 1.5, None, "1", [1]]),
        (
            "random_state",
            [None, 0, 42, 2**32 - 1, np.int64(5), np.uint32(7), np.random.RandomState(0)],
            [-1, 2**32, True, 1.0, "0", np.random.default_rng(0), np.random.SeedSequence(0)],
        ),
    ],
)
def test_named_constraints(constraint, good, bad):
    for value in good:
        assert accepts([constraint], value), (constraint, value)
    for value in bad:
        assert not accepts([constraint], value), (constraint, value)


def test_unknown_or_malformed_constraints_are_code_errors_not_user_errors():
    for constraints, error in [
        (["sparse matrix"], ValueError),
        (["boolean", 3], TypeError),
        ([], TypeError),
        ("boolean", TypeError),
    ]:
        with pytest.raises(error) as info:
            check_parameter(1, constraints, name="p", owner="Owner")
        assert not isinstance(info.value, InvalidParameterError)


# ------------------------------------------------- None and class constraints
def test_none_and_classes():
    assert accepts([None], None) and not accepts([None], 0) and not accepts([None], "None")
    band = [tuple, list, None]
    for value in [(1, 2), [1, 2], (), None]:
        assert accepts(band, value)
    for value in [np.array([1, 2]), "12", {1, 2}, 3]:
        assert not accepts(band, value)
    n_jobs = [Integral, None]
    assert accepts(n_jobs, -1) and accepts(n_jobs, np.int32(4)) and accepts(n_jobs, None)
    assert not accepts(n_jobs, 2.0) and not accepts(n_jobs, "2")
    # a class constraint is isinstance and nothing more: True is an Integral
    assert accepts(n_jobs, True)


def test_estimator_class_constraint_takes_instances_and_subclasses_only():
    linear_model = [None, BLAEstimator]

    class MyBLA(BLAEstimator):
        pass

    assert accepts(linear_model, BLAEstimator(n_states=2)) and accepts(linear_model, MyBLA())
    assert accepts(linear_model, None)
    assert not accepts(linear_model, BLAEstimator)  # the class, not an instance
    assert not accepts(linear_model, PNLSSRegressor())


# ---------------------------------------------------------------- messages
def test_invalid_parameter_error_is_both_value_and_type_error():
    assert issubclass(InvalidParameterError, ValueError)
    assert issubclass(InvalidParameterError, TypeError)
    with pytest.raises(ValueError):
        check_parameter(1, ["boolean"], name="p", owner="Owner")
    with pytest.raises(TypeError):
        check_parameter(1, ["boolean"], name="p", owner="Owner")


@pytest.mark.parametrize(
    "constraints, value, allowed",
    [
        ([Interval(Integral, 2, None, closed="left")], 1, "an int in the range [2, inf)"),
        ([Interval(Integral, 2, None, closed="left"), None], 1.5, "an int in the range [2, inf) or None"),
        ([Interval(Real, 0, 1, closed="neither")], 1.0, "a float in the range (0, 1)"),
        ([None, Options(str, {"band", "noise"})], "both", "a str among {'band', 'noise'} or None"),
        (
            [Interval(Integral, 0, None, closed="left"), Options(str, {"auto"})],
            -1,
            "an int in the range [0, inf) or a str among {'auto'}",
        ),
        (["boolean", Options(str, {"auto"})], "yes", "a bool or a str among {'auto'}"),
        ([tuple, list, None], "0-1", "a tuple, a list or None"),
        ([Integral, None], 2.0, "an int or None"),
        ([None, BLAEstimator], "bla", "an instance of BLAEstimator or None"),
        (["array-like", None], 3, "an array-like (list, tuple or array) or None"),
        (["verbose"], -1, "a bool or an int in the range [0, inf)"),
        (
            ["random_state"],
            -1,
            "None, an int in the range [0, 4294967295] or an instance of numpy.random.RandomState",
        ),
    ],
)
def test_messages_list_what_is_allowed(constraints, value, allowed):
    text = message(constraints, value, name="degree", owner="DecoupledPNLSSRegressor")
    assert text == (
        f"The 'degree' parameter of DecoupledPNLSSRegressor must be {allowed}. Got {value!r} instead."
    )


def test_long_values_are_shortened_in_messages():
    text = message(["boolean"], list(range(1000)))
    assert len(text) < 200 and text.endswith("... instead.")


# ---------------------------------------------- validate_parameters / decorator
class Toy(BaseEstimator):
    _parameter_constraints = {
        "alpha": [Interval(Real, 0, None, closed="neither")],
        "mode": [Options(str, {"a", "b"}), None],
        "not_a_parameter": ["boolean"],
    }

    def __init__(self, alpha=1.0, mode="a", free=None):
        self.alpha = alpha
        self.mode = mode
        self.free = free

    @validates_parameters
    def fit(self, X, y=None, *, sample_weight=None):
        """Fit the toy."""
        self.fit_calls_ = getattr(self, "fit_calls_", 0) + 1
        self.seen_ = (X, y, sample_weight)
        return self


def test_validate_parameters_checks_the_declared_parameters_only():
    validate_parameters(Toy(free=object()))  # "free" is not in the dict: not checked
    validate_parameters(Toy(mode=None))
    with pytest.raises(InvalidParameterError, match=r"^The 'alpha' parameter of Toy must be a float "
                                                     r"in the range \(0, inf\)\. Got 0 instead\.$"):
        validate_parameters(Toy(alpha=0))
    with pytest.raises(InvalidParameterError, match="The 'mode' parameter of Toy"):
        validate_parameters(Toy(mode="c"))


def test_validate_parameters_needs_a_constraints_dict():
    class NoConstraints(BaseEstimator):
        def __init__(self, a=1):
            self.a = a

    with pytest.raises(TypeError, match="NoConstraints declares no _parameter_constraints"):
        validate_parameters(NoConstraints())


def test_decorator_validates_before_fitting_and_keeps_fit_as_it_was():
    toy = Toy(alpha=-1.0)
    with pytest.raises(InvalidParameterError, match="'alpha'"):
        toy.fit("X")
    assert not hasattr(toy, "fit_calls_")  # fit never started
    toy.set_params(alpha=2.0)
    assert toy.fit("X", "y", sample_weight="w") is toy
    assert toy.seen_ == ("X", "y", "w") and toy.fit_calls_ == 1
    assert Toy.fit.__name__ == "fit" and Toy.fit.__doc__ == "Fit the toy."
    assert list(inspect.signature(Toy.fit).parameters) == ["self", "X", "y", "sample_weight"]


# --------------------------------------------------------- the estimators
@pytest.mark.parametrize(
    "estimator, expected",
    [
        (BLAEstimator(n_states=0), "The 'n_states' parameter of BLAEstimator must be an int in the range "
                                   "[1, inf). Got 0 instead."),
        (BLAEstimator(period=1), "The 'period' parameter of BLAEstimator must be an int in the range "
                                 "[2, inf) or None. Got 1 instead."),
        (BLAEstimator(fs=0.0), "The 'fs' parameter of BLAEstimator must be a float in the range "
                               "(0, inf) or None. Got 0.0 instead."),
        (BLAEstimator(refine=1), "The 'refine' parameter of BLAEstimator must be a bool. Got 1 instead."),
        (BLAEstimator(lines=5), "The 'lines' parameter of BLAEstimator must be an array-like (list, tuple "
                                "or array) or None. Got 5 instead."),
        (BLAEstimator(n_states=True), "The 'n_states' parameter of BLAEstimator must be an int in the "
                                      "range [1, inf). Got True instead."),
        # the same message as scikit-learn's validation gave (the other
        # estimators move to this module in the same change)
        (DecoupledPNLSSRegressor(degree=1), "The 'degree' parameter of DecoupledPNLSSRegressor must be "
                                            "an int in the range [2, inf). Got 1 instead."),
        (PNLSSRegressor(max_iter=-1), "The 'max_iter' parameter of PNLSSRegressor must be an int in the "
                                      "range [0, inf). Got -1 instead."),
    ],
)
def test_estimators_reject_bad_parameters_at_fit_before_reading_data(estimator, expected):
    with pytest.raises(ValueError) as info:
        estimator.fit(None, None)
    assert str(info.value) == expected


def test_bla_validates_with_this_module():
    with pytest.raises(InvalidParameterError):
        BLAEstimator(nperseg=2).fit(None, None)


def test_bla_defaults_and_typical_settings_are_valid():
    validate_parameters(BLAEstimator())
    validate_parameters(BLAEstimator(n_states=np.int64(4), period=256, fs=100, lines=np.arange(1, 20),
                                     refine=np.False_, feedthrough=False, n_block_rows=8, nperseg=64))


ESTIMATORS = sorted(
    name for name in sklearn_pnlss.__all__
    if inspect.isclass(getattr(sklearn_pnlss, name)) and issubclass(getattr(sklearn_pnlss, name), BaseEstimator)
)


@pytest.mark.parametrize("name", [*ESTIMATORS, "gap.GapDiagnosis", "gap.StructuralGapDiagnosis", "gap.ConnectionLocator"])
def test_constraints_name_exactly_the_parameters(name):
    """A parameter missing from the dict would go unchecked, and a name in
    the dict that is no parameter would be a typo."""
    module, _, attr = name.rpartition(".")
    cls = getattr(importlib.import_module(f"sklearn_pnlss.{module}".rstrip(".")), attr)
    assert set(cls._parameter_constraints) == set(inspect.signature(cls).parameters)


# ------------------------------------------- no private scikit-learn names
# The brief's patterns, tightened: "sklearn" must be the package itself (not
# sklearn_pnlss), and dunders such as sklearn.__version__ are public.
FROM_PRIVATE_NAME = re.compile(r"\bfrom\s+sklearn(?:\.[\w.]*)?\s+import\s+\(?\s*_(?!_)")
PRIVATE_DOTTED = re.compile(r"\bsklearn(?:\.\w+)*\.(_\w+)")


def _private(name):
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def private_sklearn_uses(source):
    """(line, text) of every private scikit-learn module or name the source
    imports or spells out: the two patterns above, line by line, and the
    import statements themselves (which also catch ``from sklearn.base
    import BaseEstimator, _fit_context`` and imports over several lines)."""
    found = set()
    lines = source.splitlines()
    for number, line in enumerate(lines, 1):
        dotted = [m.group(1) for m in PRIVATE_DOTTED.finditer(line)]
        if FROM_PRIVATE_NAME.search(line) or any(_private(name) for name in dotted):
            found.add((number, line.strip()))
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            paths = [node.module.split(".") + [alias.name] for alias in node.names]
        elif isinstance(node, ast.Import):
            paths = [alias.name.split(".") for alias in node.names]
        else:
            continue
        if any(path[0] == "sklearn" and any(map(_private, path[1:])) for path in paths):
            found.add((node.lineno, lines[node.lineno - 1].strip()))
    return sorted(found)


@pytest.mark.parametrize(
    "source",
    [
        "from sklearn.base import _fit_context",
        "from sklearn.base import BaseEstimator, _fit_context",
        "from sklearn.base import (\n    BaseEstimator,\n    _fit_context,\n)",
        "from sklearn.utils._param_validation import Interval, StrOptions",
        "from sklearn._config import get_config",
        "import sklearn.utils._param_validation as pv",
        "import sklearn\nsklearn.base._fit_context(prefer_skip_nested_validation=True)",
        "x = sklearn.utils._tags.Tags",
    ],
)
def test_scanner_finds_private_uses(source):
    assert private_sklearn_uses(source)


@pytest.mark.parametrize(
    "source",
    [
        "from sklearn.base import BaseEstimator, clone",
        "from sklearn.utils.validation import check_is_fitted",
        "import sklearn\nv = sklearn.__version__",
        "from sklearn_pnlss.estimators._base import SignalRegressorBase",
        "from ..utils._private import thing",
        "from sklearn_pnlss.statespace import _pnlss_kernels",
        "import sklearn_pnlss._internal",
    ],
)
def test_scanner_leaves_public_and_own_names_alone(source):
    assert private_sklearn_uses(source) == []


def _offenders(files):
    return {
        str(path.relative_to(PACKAGE.parent)): uses
        for path in files
        if (uses := private_sklearn_uses(path.read_text(encoding="utf-8")))
    }


def test_library_uses_public_scikit_learn_only():
    """scikit-learn may change or remove a private name in any release;
    pyproject.toml puts no upper bound on it, so the library must not rely
    on one."""
    assert _offenders(sorted(PACKAGE.rglob("*.py"))) == {}
