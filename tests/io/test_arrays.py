"""Array sidecars: same arrays, same bytes; a header refuses a sidecar it was not written with."""

import numpy as np
import pytest
import yaml

from posegen.errors import InputError
from posegen.io import encode_arrays, read_arrays, write_with_arrays

ARRAYS = {"a": np.arange(6, dtype=np.int64), "b": np.linspace(0.0, 1.0, 12).reshape(4, 3)}


def test_same_arrays_same_bytes():
    assert encode_arrays(ARRAYS) == encode_arrays({k: v.copy() for k, v in ARRAYS.items()})
    assert encode_arrays(ARRAYS) != encode_arrays({**ARRAYS, "a": ARRAYS["a"] + 1})


def test_round_trip_is_exact(tmp_path):
    path = tmp_path / "thing.yaml"
    values = {"x": np.random.default_rng(0).normal(size=(5, 7))}
    write_with_arrays(path, {"format": "test"}, values)
    header = yaml.safe_load(path.read_text())
    name = header["arrays"]["file"]
    assert name == f"thing.yaml.{header['arrays']['sha256'][:12]}.npz"  # named by its content
    again = read_arrays(path, header["arrays"], ("x",))
    assert again["x"].tobytes() == values["x"].tobytes()
    assert np.load(tmp_path / name)["x"].shape == (5, 7)  # any numpy reads it


def test_changed_missing_or_incomplete_sidecar_is_refused(tmp_path):
    path = tmp_path / "thing.yaml"
    write_with_arrays(path, {"format": "test"}, ARRAYS)
    reference = yaml.safe_load(path.read_text())["arrays"]
    sidecar = tmp_path / reference["file"]
    with pytest.raises(InputError, match="missing arrays c"):
        read_arrays(path, reference, ("a", "c"))
    with pytest.raises(InputError, match="must name its sidecar"):
        read_arrays(path, "thing.npz", ("a",))
    sidecar.write_bytes(encode_arrays({**ARRAYS, "a": ARRAYS["a"] * 2}))
    with pytest.raises(InputError, match="sha256 differs"):
        read_arrays(path, reference, ("a",))
    sidecar.unlink()
    with pytest.raises(InputError, match="cannot read"):
        read_arrays(path, reference, ("a",))
    (tmp_path / "thing.npz").write_bytes(b"not a zip")
    with pytest.raises(InputError):
        read_arrays(
            path, {"file": "thing.npz", "sha256": __import__("hashlib").sha256(b"not a zip").hexdigest()}, ("a",)
        )


def test_a_compressed_sidecar_keeps_values_memory_order_and_determinism(tmp_path):
    series = {"t": np.linspace(0.0, 9.0, 400), "q": np.asfortranarray(np.cumsum(np.ones((400, 6)), axis=0))}
    packed = encode_arrays(series, compress=True)
    assert packed == encode_arrays({k: v.copy(order="K") for k, v in series.items()}, compress=True)
    assert len(packed) < len(encode_arrays(series)) / 2
    path = tmp_path / "series.yaml"
    write_with_arrays(path, {"format": "test"}, series, compress=True)
    back = read_arrays(path, yaml.safe_load(path.read_text())["arrays"], ("t", "q"))
    assert np.array_equal(back["q"], series["q"]) and back["q"].flags.f_contiguous
