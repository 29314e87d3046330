"""The datasets the harness compares the laws with: where each comes from, how to cite it,
its files' SHA-256, and where a user's copy is found.

Measured data the project may not redistribute (no licence) is never shipped: a user points
the harness at a copy (``--data PATH`` or an environment variable); its files are checked
against the published SHA-256 before anything is read, and the hashes go into provenance.
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass
from pathlib import Path


class DataMissing(LookupError):
    """No copy of a dataset was given: the message says where to get one."""


class DataInvalid(ValueError):
    """A copy was given but is not the dataset (a file absent or a checksum differs)."""


@dataclass(frozen=True)
class DataFile:
    name: str
    sha256: str
    source: str  # repository @ commit, path: where the file is published


@dataclass(frozen=True)
class Dataset:
    name: str
    citation: str
    licence: str
    where_to_get: str
    env_var: str | None  # None: the data is a cited table inside the project
    files: tuple[DataFile, ...] = ()
    quality_flags: tuple[tuple[str, str], ...] = ()  # (flag, meaning)


FAZELI_2017 = Dataset(
    name="fazeli2017",
    citation=("N. Fazeli, E. Donlon, E. Drumwright, A. Rodriguez, \"Empirical evaluation of "
              "common contact models for planar impact\", IEEE ICRA 2017"),
    licence="none published: not redistributed; the harness reads a user's copy",
    where_to_get=("https://github.com/mcubelab/planar-impact-dataset (processed_data/"
                  "data_ellipse.mat, v_models.mat) and https://github.com/Nima-Fazeli/"
                  "contact_models_and_data (data/ellipse_uniform.mat); put the three files "
                  "in one directory and pass it as --data DIR or IMPACT_HARNESS_FAZELI_DIR"),
    env_var="IMPACT_HARNESS_FAZELI_DIR",
    files=(
        DataFile("data_ellipse.mat",
                 "06ecb1642369b0e013f6f8ba7761797529c3de5e8d70d913722b118572afb169",
                 "mcubelab/planar-impact-dataset @ f24a7e3, processed_data/"),
        DataFile("v_models.mat",
                 "22ebce5783dbb4024e34d2bba05c1c08a30f29cf2473c6dc80a152bd77a677f6",
                 "mcubelab/planar-impact-dataset @ f24a7e3, processed_data/"),
        DataFile("ellipse_uniform.mat",
                 "fafcb329cca4325659ca384bc9a3f43057608f21a178d37e45eefd6032ddf224",
                 "Nima-Fazeli/contact_models_and_data @ fac1be5, data/"),
    ),
    # The authors' processing script sets these per raw drop; a drop is processed (one of
    # the 1,718) exactly when every flag is 0.
    quality_flags=(
        ("sb", "no second bounce found after the impact (post-impact fit window guessed)"),
        ("en", "kinetic energy gained in the impact"),
        ("cl", "measured impulse outside the friction cone of mu = 0.35"),
        ("mc", "measured impulse beyond the maximum-compression line"),
        ("de", "dropped early: the first detected impact too close to the recording's start"),
        ("ld", "frames lost near the impact (the impact taken from a later detection)"),
    ),
)

KHARAZ_2001 = Dataset(
    name="kharaz2001",
    citation=("A. H. Kharaz, D. A. Gorham, A. D. Salman, \"An experimental study of the "
              "elastic rebound of spheres\", Powder Technology 120 (2001) 281-291"),
    licence=("published measurements, cited as a small table of points others digitised "
             "from the figures (harness/experiments/kharaz.py names them)"),
    where_to_get="inside the harness (harness/experiments/kharaz.py)",
    env_var=None,
)

DATASETS = {dataset.name: dataset for dataset in (FAZELI_2017, KHARAZ_2001)}


def sha256_of(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def locate(dataset: Dataset, path: str | os.PathLike | None = None) -> Path:
    """The directory of a user's copy: ``path`` if given, else the dataset's environment
    variable. Raises :class:`DataMissing` (neither given) or :class:`DataInvalid` (given but
    not a directory)."""
    if path is None and dataset.env_var:
        path = os.environ.get(dataset.env_var) or None
    if path is None:
        raise DataMissing(f"{dataset.name}: no copy given (--data DIR or {dataset.env_var}); "
                          f"get it from {dataset.where_to_get}")
    directory = Path(path)
    if not directory.is_dir():
        raise DataInvalid(f"{dataset.name}: {directory}: not a directory (expected the "
                          f"directory holding {', '.join(f.name for f in dataset.files)})")
    return directory


def verify(dataset: Dataset, directory: Path) -> dict[str, str]:
    """``{file name: SHA-256}`` of the copy in ``directory``, every file checked against the
    published hash first; raises :class:`DataInvalid` naming the file and both hashes."""
    hashes = {}
    for data_file in dataset.files:
        path = directory / data_file.name
        if not path.is_file():
            raise DataInvalid(f"{dataset.name}: {path}: missing (from {data_file.source})")
        found = sha256_of(path)
        if found != data_file.sha256:
            raise DataInvalid(f"{dataset.name}: {path}: SHA-256 {found} is not the published "
                              f"file's {data_file.sha256} ({data_file.source})")
        hashes[data_file.name] = found
    return hashes


def provenance(dataset: Dataset, directory: Path | None, hashes: dict[str, str]) -> dict:
    """What an output records about the data it used: name, citation, directory, hashes."""
    return {"dataset": dataset.name, "citation": dataset.citation,
            "directory": None if directory is None else str(directory), "sha256": hashes}
