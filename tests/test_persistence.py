"""Saving and loading fitted models: identical predictions after the round
trip, and a clear refusal of files from incompatible versions."""
import warnings

import joblib
import numpy as np
import pytest

import sklearn_pnlss
from sklearn_pnlss import persistence
from sklearn_pnlss.persistence import IncompatibleModelFileError, load, read_header, save


@pytest.mark.parametrize("compress", [0, 3])
def test_round_trip_predicts_identically(small_pipeline, small_data, tmp_path, compress):
    path = save(small_pipeline, tmp_path / "model.joblib", compress=compress)
    loaded = load(path)
    X = [small_data.X_val[0], small_data.X_val[0, :300]]  # steady state, and from rest
    for a, b in zip(loaded.predict(X), small_pipeline.predict(X)):
        np.testing.assert_array_equal(a, b)
    # Every stage, its fitted attributes and its summary survive.
    for before, after in zip(small_pipeline, loaded):
        assert type(after) is type(before) and after.get_params(deep=False).keys() == before.get_params(deep=False).keys()
        np.testing.assert_array_equal(after.A_, before.A_)
        assert str(after.summary()) == str(before.summary())


def test_each_estimator_round_trips_on_its_own(small_pipeline, small_data, tmp_path):
    for i, est in enumerate(small_pipeline):
        loaded = load(save(est, tmp_path / f"stage{i}.joblib"))
        np.testing.assert_array_equal(loaded.predict(small_data.X_val), est.predict(small_data.X_val))


def test_a_model_pickled_before_a_parameter_existed_loads_with_its_default(small_pipeline, small_data):
    import pickle

    for est in small_pipeline[1:]:
        state = est.__getstate__()
        del state["stable_at_rest"]  # as a model pickled before the parameter came
        old = type(est).__new__(type(est))
        old.__setstate__(pickle.loads(pickle.dumps(state)))
        assert old.get_params()["stable_at_rest"] is False and repr(old)
        np.testing.assert_array_equal(old.predict(small_data.X_val), est.predict(small_data.X_val))


def test_header_records_the_versions(small_pipeline, tmp_path):
    import sklearn

    header = read_header(save(small_pipeline[0], tmp_path / "bla.joblib"))
    assert header["library_version"] == sklearn_pnlss.__version__
    assert header["format_version"] == persistence.FORMAT_VERSION
    assert header["sklearn_version"] == sklearn.__version__


def _save_as(monkeypatch, model, path, *, version=None, fmt=None):
    """A file as another version of the library would write it."""
    with monkeypatch.context() as m:
        if version is not None:
            m.setattr(persistence, "__version__", version)
        if fmt is not None:
            m.setattr(persistence, "FORMAT_VERSION", fmt)
        return save(model, path)


def test_load_refuses_another_release_series_naming_both_versions(small_pipeline, tmp_path, monkeypatch):
    path = _save_as(monkeypatch, small_pipeline[0], tmp_path / "old.joblib", version="7.3.1")
    with pytest.raises(IncompatibleModelFileError) as exc:
        load(path)
    message = str(exc.value)
    assert "7.3.1" in message and sklearn_pnlss.__version__ in message
    assert "sklearn_pnlss==7.3.*" in message and "fit the model" in message
    assert isinstance(exc.value, ValueError)


def test_load_refuses_another_file_format(small_pipeline, tmp_path, monkeypatch):
    path = _save_as(monkeypatch, small_pipeline[0], tmp_path / "other.joblib", fmt=persistence.FORMAT_VERSION + 1)
    with pytest.raises(IncompatibleModelFileError, match=f"file format {persistence.FORMAT_VERSION + 1}"):
        load(path)


def test_load_accepts_another_patch_release(small_pipeline, tmp_path, monkeypatch):
    major, minor = sklearn_pnlss.__version__.split(".")[:2]
    path = _save_as(monkeypatch, small_pipeline[0], tmp_path / "patch.joblib", version=f"{major}.{minor}.99")
    assert load(path).n_params_ == small_pipeline[0].n_params_


def test_load_refuses_files_that_are_not_model_files(small_pipeline, tmp_path):
    plain = tmp_path / "plain.joblib"
    joblib.dump(small_pipeline[0], plain)
    with pytest.raises(IncompatibleModelFileError, match="not a model file written by"):
        load(plain)
    garbage = tmp_path / "garbage.joblib"
    garbage.write_bytes(b"not a pickle at all")
    with pytest.raises(IncompatibleModelFileError, match="not a model file"):
        load(garbage)


def test_another_scikit_learn_version_warns(small_pipeline, tmp_path):
    path = tmp_path / "sk.joblib"
    header = {**persistence._header(), "sklearn_version": "0.0.1"}
    with open(path, "wb") as fh:
        joblib.dump(header, fh)
        joblib.dump(small_pipeline[0], fh)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = load(path)
    assert any("scikit-learn 0.0.1" in str(w.message) for w in caught)
    assert model.n_params_ == small_pipeline[0].n_params_
