"""The survey streamed to disk: chunk by chunk into a partitioned Parquet dataset, its
statistics computed from the dataset out of core, resumable, on local cores or Dask.

A *chunk* is a range of sample indices, the same range of every population
(:func:`chunk_bounds`: its size depends on the samples and the number of populations only,
never on the workers, so a survey run again finds the same chunks). Each chunk is sampled,
solved by every law, run through every engine and preset and judged where it runs
(:func:`run_chunk`, one task of :func:`harness.run.executor.run_tasks`), and this process
writes it as soon as it arrives (:func:`ChunkWriter`), then drops it. The dataset, under
``OUT/dataset/`` (:data:`DATASET`):

* ``runs/engine=E/preset=P/part-NNNNN.parquet`` -- the chunk's runs of one pair (the
  columns of ``runs.parquet``);
* ``samples/part-NNNNN.parquet`` -- the chunk's samples;
* ``chunks/part-NNNNN.json`` -- the chunk's rejected draws, timings, skipped runs and engine
  errors (each errored run's pair, family, sample and reason), written last: a chunk is done
  when its JSON exists (every file is written atomically);
* ``plan.json`` -- what is surveyed (populations' texts, samples, seed, pairs, settings,
  chunks, the code and the installed versions): a survey run again with the same plan
  continues from the chunks done; another plan clears the dataset (the files above only)
  first.

Every Parquet file carries the survey's metadata (:func:`harness.survey.cli.table_metadata`)
and a row group per population (a chunk's rows are population after population);
``pyarrow.dataset.dataset("OUT/dataset/runs", partitioning="hive")`` reads the runs of every
chunk at once.

Statistics out of core (:func:`dataset_statistics`): for one engine × preset × family at a
time, the columns the statistics need are read from the dataset (the family's row group of
each chunk file; texts shared: ~100 bytes a run), ordered by sample, and given to
:func:`harness.survey.statistics.statistics`: the rows and bits of the statistics of the
survey held in memory (tests/survey/test_stream.py). Peak memory is therefore one chunk per
worker (its scenes, runs and contact records: :data:`CHUNK_IMPACTS` impacts at most) plus,
in this process, the largest engine × preset × family group (~100 bytes a run) and a
bootstrap block (:data:`harness.survey.statistics.BOOTSTRAP_BLOCK`); the whole tables
``runs.parquet`` and ``samples.parquet`` are written a row group at a time
(:func:`concatenate`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from harness.run.executor import run_tasks
from harness.run.provenance import package_versions
from harness.scenarios.errors import ScenarioError
from harness.store.files import write_text_atomically
from harness.store.identity import cached_code_sources, code_version_of
from harness.survey import laws as survey_laws
from harness.survey import outputs, statistics
from harness.survey.engines import ERROR, SKIPPED
from harness.survey.parts import MIN_PART, compute_part
from harness.survey.sampling import REJECTIONS

#: The dataset's directory under the survey's ``--out``.
DATASET = "dataset"
#: Most impacts (samples × populations) in one chunk: a worker holds one chunk's scenes,
#: runs and contact records at a time (tens of KB an impact), a kill loses at most a chunk
#: per worker, and the per-chunk cost (a task, a few files) stays small beside its runs.
CHUNK_IMPACTS = 512
#: Chunks a survey is cut into at least (when it has the samples): both cores busy to the end.
MIN_CHUNKS = 16
#: Seconds one chunk may run by default (``--task-time-limit``): a chunk of
#: :data:`CHUNK_IMPACTS` takes 5-60 s on the 2-core machine (MuJoCo's matched-bounce the
#: longest); one 20 times slower is stuck (a population whose draws never approach).
CHUNK_TIME_LIMIT_S = 1200.0
#: Samples per population the figures draw (the first ones): a figure of more points says
#: no more, and drawing them all would hold every run in memory.
FIGURE_SAMPLES = 2000
#: Rows per row group of the whole tables (``runs.parquet``, ``samples.parquet``): a chunk's
#: family is tens of rows, and a writer keeps every row group's metadata until it closes
#: (a million impacts in row groups of 73 rows held 600 MB of it), while a row group of the
#: samples' ~60 columns is gathered whole (65,536 rows: 75 MB more at the peak).
ROW_GROUP_ROWS = 16384
#: Columns the statistics read from the dataset.
STATISTICS_COLUMNS = ("engine", "preset", "family", "sample", "status", "reasons",
                      "poisson_type", "gains_energy", "departure_poisson",
                      "departure_stronge", "law_part", "solve_part")
#: Columns the figures read.
FIGURE_COLUMNS = ("engine", "preset", "family", "sample", "status", "poisson_type",
                  "alpha_over_rm", "mu", "departure_poisson")


def chunk_bounds(samples: int, populations: int) -> list[tuple[int, int]]:
    """``[(begin, end), …]``: the chunks' sample ranges. At least :data:`MIN_CHUNKS` when
    there are samples for them (:data:`harness.survey.parts.MIN_PART` samples each at the
    fewest), at most :data:`CHUNK_IMPACTS` impacts each."""
    largest = max(MIN_PART, CHUNK_IMPACTS // max(1, populations))
    size = min(largest, max(MIN_PART, -(-samples // MIN_CHUNKS)))
    return [(begin, min(samples, begin + size)) for begin in range(0, samples, size)]


@dataclass
class ChunkOutput:
    """One chunk's results, as a worker sends them back (arrays, no scenes)."""

    index: int
    bounds: tuple[int, int]
    samples: dict | None = None  # columns of samples.parquet
    runs: list | None = None  # per pair, columns of runs.parquet
    rejections: list | None = None  # per population, {reason: draws}
    timings: dict = dataclasses.field(default_factory=dict)  # stage -> seconds on one core
    skipped: dict = dataclasses.field(default_factory=dict)  # "engine preset" -> why
    skipped_counts: dict = dataclasses.field(default_factory=dict)  # pair -> {family: runs}
    errors: list = dataclasses.field(default_factory=list)  # [pair, family, sample, why]
    cpu_s: float = 0.0
    refused: dict | None = None  # a ScenarioError's fields and its sample
    stopped: str = ""  # why the chunk was stopped (time limit, worker died)

    def release(self) -> None:
        """Drop the columns once written: ``run_tasks`` keeps every result it delivered."""
        self.samples = self.runs = None


@dataclass(frozen=True)
class ChunkTask:
    """What a worker needs for one chunk (pickled to Dask workers: populations as read,
    so a worker needs the harness and the engines installed, not the population files)."""

    index: int
    bounds: tuple[int, int]
    populations: tuple
    seed: int
    pairs: tuple
    overrides: dict
    bare: bool = False


def run_chunk(task: ChunkTask) -> ChunkOutput:
    """Sample, solve, run and judge one chunk (a top-level function: a task of
    :func:`harness.run.executor.run_tasks`)."""
    cpu = time.process_time()
    part = compute_part(task.populations, task.seed, task.pairs, task.overrides, task.bounds,
                        bare=task.bare)
    if part.refused is not None:
        position, sample, fields = part.refused
        return ChunkOutput(task.index, task.bounds,
                           refused={"population": position, "sample": sample, **fields})
    tick = time.perf_counter()
    terms = part.terms
    law_results = survey_laws.solve_laws(terms)
    routh = survey_laws.routh_coordinates(terms)
    family = np.asarray([row.population for row in part.rows])
    index = np.asarray([row.index for row in part.rows])
    samples = sample_columns(part.rows, terms, law_results, routh)
    runs = [statistics.run_columns(family, index, terms, law_results, routh, [result])
            for result in part.results]
    timings = dict(part.timings)
    timings["laws"] += time.perf_counter() - tick
    for result in part.results:
        timings[f"engine {result.engine} {result.preset}"] = result.wall_s
        timings[f"verdicts {result.engine} {result.preset}"] = result.judge_s
    skipped = {f"{result.engine} {result.preset}": result.skipped_why
               for result in part.results if result.skipped_why}
    counts: dict[str, dict[str, int]] = {}
    for result, columns in zip(part.results, runs):
        refused = columns["family"][columns["status"] == SKIPPED].tolist()
        for family in refused:
            found = counts.setdefault(f"{result.engine} {result.preset}", {})
            found[family] = found.get(family, 0) + 1
    errors = [[f"{result.engine} {result.preset}", str(columns["family"][row]),
               int(columns["sample"][row]), str(columns["error"][row])]
              for result, columns in zip(part.results, runs)
              for row in np.flatnonzero(columns["status"] == ERROR).tolist()]
    return ChunkOutput(task.index, task.bounds, samples, runs, part.rejections, timings,
                       skipped, counts, errors, time.process_time() - cpu)


def sample_columns(every, terms, law_results, routh) -> dict:
    """Columns of ``samples.parquet`` (``every``: the samples, or their
    :class:`harness.survey.parts.SampleRow`)."""
    columns = {
        "family": np.asarray([s.population for s in every]),
        "sample": np.asarray([s.index for s in every]),
        "attempts": np.asarray([s.attempts for s in every]),
    }
    # The drawn parameters, NaN where a sample has none of that name; the samples of one
    # population draw the same names in the same order, so they fill the columns as a block.
    blocks: dict[tuple, list[int]] = {}
    for row, sample in enumerate(every):
        blocks.setdefault(tuple(sample.parameters), []).append(row)
    keys = list(dict.fromkeys(key for names in blocks for key in names))
    columns.update((key, np.full(len(every), np.nan)) for key in keys)
    for names, rows in blocks.items():
        values = np.array([list(every[row].parameters.values()) for row in rows], dtype=float)
        for place, key in enumerate(names):
            columns[key][rows] = values[:, place]
    for key in ("mnn", "mnt", "mtt", "vn", "vt"):
        columns[key] = getattr(terms, key)
    columns.update(routh)
    poisson = law_results["poisson"].u_after
    scales = statistics.row_scales(terms)
    for law, result in law_results.items():
        columns[f"{law}.status"] = result.batch.status.astype(np.int64)
        columns[f"{law}.collision_type"] = result.batch.collision_type.astype(np.int64)
        columns[f"{law}.energy_change"] = result.batch.energy_change
        columns[f"{law}.from_poisson"] = statistics.row_departures(terms, result.u_after, poisson,
                                                                   scales)
    return columns


def plan_of(populations, samples: int, seed: int, pairs, overrides: dict) -> dict:
    """What a survey's dataset holds the chunks of: a chunk written under one plan is
    reused only under the same plan (the populations by their files' text, the code of
    the engines, verdicts, solver and survey, the installed versions)."""
    texts = []
    for population in populations:
        path = getattr(population, "path", None)
        try:
            text = Path(path).read_bytes() if path else repr(population).encode()
        except OSError:
            text = repr(population).encode()
        texts.append([population.name, hashlib.sha256(text).hexdigest()])
    return {"format": "impact-harness-survey-dataset", "code": code_version_of(
                (*cached_code_sources(), Path(__file__).resolve().parent)),
            "versions": package_versions(), "populations": texts,
            "samples": samples, "seed": seed, "pairs": [list(pair) for pair in pairs],
            "overrides": overrides, "chunks": [list(b) for b in
                                               chunk_bounds(samples, len(populations))]}


def _part_name(index: int, suffix: str) -> str:
    return f"part-{index:05d}.{suffix}"


def _pair_directory(dataset: Path, engine: str, preset: str) -> Path:
    return dataset / "runs" / f"engine={engine}" / f"preset={preset}"


def _harness_files(dataset: Path) -> list[Path]:
    """The files a survey writes in its dataset (only those: nothing else is removed)."""
    found = [dataset / "plan.json"]
    for pattern in ("samples/part-*.parquet", "chunks/part-*.json",
                    "runs/engine=*/preset=*/part-*.parquet"):
        found += sorted(dataset.glob(pattern))
    return [path for path in found if path.is_file() and not path.is_symlink()]


def _directory(path: Path) -> Path:
    """``path`` made (with its parents under the dataset); a link there is refused."""
    if path.is_symlink():
        raise ValueError(f"{path}: a symbolic link, not a directory the survey made")
    path.mkdir(parents=True, exist_ok=True)
    return path


def open_dataset(out: Path, plan: dict) -> tuple[Path, set[int]]:
    """The dataset directory under ``out`` for ``plan`` and the chunks already done there
    (those of an earlier run of the same plan); another plan's files are removed first."""
    dataset = _directory(out / DATASET)
    plan_path = dataset / "plan.json"
    try:
        found = json.loads(plan_path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        found = None
    if found == json.loads(json.dumps(plan)):
        done = {int(path.stem.split("-")[1]) for path in (dataset / "chunks").glob("part-*.json")
                if path.is_file()}
        return dataset, done
    for path in _harness_files(dataset):
        path.unlink()
    write_text_atomically(plan_path, json.dumps(plan, indent=1) + "\n")
    return dataset, set()


class ChunkWriter:
    """Writes each chunk as it arrives (``on_result`` of ``run_tasks``), then drops it."""

    def __init__(self, dataset: Path, pairs, metadata: dict, progress: Progress | None):
        self.dataset = dataset
        self.pairs = list(pairs)
        self.metadata = metadata
        self.progress = progress
        self.stopped: dict[int, str] = {}

    def __call__(self, _position: int, output: ChunkOutput) -> None:
        if output.refused is not None:
            fields = dict(output.refused)
            sample = fields.pop("sample")
            fields.pop("population")
            error = ScenarioError(**fields)
            error.sample = sample
            raise error
        if output.stopped:
            self.stopped[output.index] = output.stopped
        else:
            self.write(output)
        if self.progress is not None:
            self.progress.chunk_done(output.bounds, stopped=bool(output.stopped))

    def write(self, output: ChunkOutput) -> None:
        name = _part_name(output.index, "parquet")
        # A row group per population (the chunk's rows are population after population, the
        # same count of each): a family's rows are read without the others'.
        size = output.bounds[1] - output.bounds[0]
        for (engine, preset), columns in zip(self.pairs, output.runs):
            directory = _directory(_pair_directory(self.dataset, engine, preset))
            outputs.write_parquet(columns, directory / name, {**self.metadata, "table": "runs"},
                                  row_group_size=size)
        outputs.write_parquet(output.samples, _directory(self.dataset / "samples") / name,
                              {**self.metadata, "table": "samples"}, row_group_size=size)
        record = {"bounds": list(output.bounds), "rejections": output.rejections,
                  "timings": output.timings, "skipped": output.skipped,
                  "skipped_counts": output.skipped_counts, "errors": output.errors,
                  "cpu_s": output.cpu_s}
        write_text_atomically(_directory(self.dataset / "chunks")
                              / _part_name(output.index, "json"),
                              json.dumps(record, indent=1) + "\n")
        output.release()


class Progress:
    """Progress on stderr: chunks and impacts done, elapsed, and an estimate of the time left
    (the time per impact of this run so far, times the impacts to go)."""

    def __init__(self, total_impacts: int, done_impacts: int, populations: int,
                 stream=None, every_s: float = 2.0):
        self.total = total_impacts
        self.done = done_impacts
        self.populations = populations
        self.start_done = done_impacts
        self.stream = sys.stderr if stream is None else stream
        self.begin = time.perf_counter()
        self.every_s = every_s
        self.last = -float("inf")

    def chunk_done(self, bounds, stopped: bool = False) -> None:
        self.done += (bounds[1] - bounds[0]) * self.populations
        now = time.perf_counter()
        if now - self.last < self.every_s and self.done < self.total:
            return
        self.last = now
        elapsed = now - self.begin
        ran = self.done - self.start_done
        left = elapsed / ran * (self.total - self.done) if ran else float("nan")
        print(f"survey: {self.done:,}/{self.total:,} impacts ({100 * self.done / self.total:.0f}%)"
              f", {_duration(elapsed)} elapsed, about {_duration(left)} left"
              + (" (a chunk stopped)" if stopped else ""), file=self.stream, flush=True)


def _duration(seconds: float) -> str:
    if not np.isfinite(seconds):
        return "?"
    seconds = int(round(seconds))
    if seconds >= 3600:
        return f"{seconds // 3600}h{seconds % 3600 // 60:02d}m"
    return f"{seconds // 60}m{seconds % 60:02d}s" if seconds >= 60 else f"{seconds}s"


def _stopped_output(task: ChunkTask, reason: str) -> ChunkOutput:
    return ChunkOutput(task.index, task.bounds, stopped=reason)


def stream_survey(populations, samples: int, seed: int, pairs, out: Path, metadata: dict, *,
                  overrides: dict | None = None, workers: int | None = None,
                  executor: str = "local", scheduler: str | None = None,
                  time_limit_s: float | None = CHUNK_TIME_LIMIT_S, bare: bool = False,
                  progress: bool = True, echo=print) -> dict:
    """Run the chunks not yet done into ``out``'s dataset; returns ``{"dataset", "done",
    "ran", "stopped", "wall_s"}`` (``stopped``: chunk index -> why, for chunks over
    ``time_limit_s`` or whose worker died: run the survey again to retry them).
    Raises the :class:`ScenarioError` of a sample that needs too many draws."""
    plan = plan_of(populations, samples, seed, pairs, dict(overrides or {}))
    dataset, done = open_dataset(out, plan)
    bounds = chunk_bounds(samples, len(populations))
    tasks = [ChunkTask(index, bound, tuple(populations), seed, tuple(pairs),
                       dict(overrides or {}), bare)
             for index, bound in enumerate(bounds) if index not in done]
    if done:
        echo(f"resuming: {len(done)} of {len(bounds)} chunks already in {dataset}")
    impacts_done = sum((bounds[i][1] - bounds[i][0]) for i in done) * len(populations)
    shown = Progress(samples * len(populations), impacts_done, len(populations)) \
        if progress else None
    writer = ChunkWriter(dataset, pairs, metadata, shown)
    begin = time.perf_counter()
    if tasks:
        run_tasks(run_chunk, tasks, executor=executor, workers=workers, scheduler=scheduler,
                  on_result=writer, chunk_size=1, dask_min_tasks=0, note=echo,
                  time_limit=(None if time_limit_s is None else lambda _task: time_limit_s),
                  stopped=_stopped_output)
    return {"dataset": dataset, "done": len(done), "ran": len(tasks),
            "stopped": writer.stopped, "wall_s": time.perf_counter() - begin,
            "chunks": len(bounds)}


def chunk_records(dataset: Path) -> list[dict]:
    """Every done chunk's JSON record, in chunk order."""
    return [json.loads(path.read_text(encoding="utf-8"))
            for path in sorted((dataset / "chunks").glob("part-*.json"))]


def totals(dataset: Path, populations) -> dict:
    """The done chunks' rejected draws per population, timings summed over chunks (seconds
    on one core), the skipped pairs' reasons and runs per family (``skipped_runs``: ``{pair:
    ({family: runs}, why)}``), the runs whose engine raised (``errors``: ``[pair, family,
    sample, why]`` by pair, family and sample), and the impacts and CPU seconds they hold."""
    rejections = {population.name: dict.fromkeys(REJECTIONS, 0) for population in populations}
    timings: dict[str, float] = {}
    skipped: dict[str, str] = {}
    skipped_counts: dict[str, dict[str, int]] = {}
    errors: list[list] = []
    impacts, cpu = 0, 0.0
    for record in chunk_records(dataset):
        for population, counts in zip(populations, record["rejections"]):
            for reason, count in counts.items():
                rejections[population.name][reason] += count
        for stage, seconds in record["timings"].items():
            timings[stage] = timings.get(stage, 0.0) + seconds
        for pair, why in record["skipped"].items():
            skipped.setdefault(pair, why)
        for pair, counts in record["skipped_counts"].items():
            found = skipped_counts.setdefault(pair, {})
            for family, count in counts.items():
                found[family] = found.get(family, 0) + count
        errors += record.get("errors", [])
        impacts += (record["bounds"][1] - record["bounds"][0]) * len(populations)
        cpu += record["cpu_s"]
    families = [population.name for population in populations]
    place = {family: position for position, family in enumerate(families)}
    errors.sort(key=lambda error: (error[0], place.get(error[1], len(place)), error[2]))
    skipped_runs = {pair: ({family: counts[family] for family in families if family in counts},
                           skipped.get(pair, ""))
                    for pair, counts in skipped_counts.items()}
    return {"rejections": rejections, "timings": timings, "skipped": skipped,
            "skipped_runs": skipped_runs, "errors": errors, "impacts": impacts, "cpu_s": cpu}


def family_blocks(directory: Path, family: str, position: int, columns=None):
    """The rows of ``family`` (the population at ``position``) in every chunk file of
    ``directory``, chunk after chunk, as pyarrow tables: each file's row group
    ``position`` (:class:`ChunkWriter` writes one per population), read alone."""
    import pyarrow.parquet as pq

    for path in sorted(directory.glob("part-*.parquet")):
        source = pq.ParquetFile(path)
        if position >= source.num_row_groups:
            continue
        block = source.read_row_group(position, columns=columns, use_threads=False)
        families = set(block.column("family").to_pylist()) if "family" in block.column_names \
            else {family}
        if families != {family}:
            raise ValueError(f"{path}: row group {position} holds {sorted(families)}, not "
                             f"{family!r}: not a chunk file of this survey")
        yield block


def pair_table(dataset: Path, engine: str, preset: str, columns, families,
               max_sample: int | None = None) -> dict:
    """``{column: array}`` of one pair's runs in the dataset, of ``families`` (``[(name,
    position among the populations)]``) and samples below ``max_sample``, ordered by family
    (as given) then sample: a row group of a file at a time (a scan of the whole dataset
    would read many files ahead: tens of MB for 80 files of 500 runs)."""
    directory = _pair_directory(dataset, engine, preset)
    wanted = list(dict.fromkeys([*columns, "family", "sample"]))
    kept: list[dict] = []
    for family, position in families:
        for block in family_blocks(directory, family, position, wanted):
            if max_sample is not None:
                block = block.filter(block.column("sample").to_numpy() < max_sample)
            if block.num_rows:
                kept.append(_columns(block))
    if not kept:
        return {}
    return {name: np.concatenate([block[name] for block in kept]) for name in columns}


def _columns(table) -> dict:
    """A table's columns as numpy arrays; ``reasons`` (a list column) comma-joined again.
    A text column becomes an object array of its few distinct texts, shared (8 bytes a
    row, not a string object each)."""
    import pyarrow as pa
    import pyarrow.compute as pc

    columns = {}
    for name in table.column_names:
        column = table.column(name)
        if pa.types.is_list(column.type):
            column = pc.binary_join(column, ",")
        if pa.types.is_string(column.type) or pa.types.is_large_string(column.type):
            encoded = column.combine_chunks().dictionary_encode()
            texts = np.asarray(encoded.dictionary.to_pylist() + [""], dtype=object)
            codes = encoded.indices.fill_null(len(texts) - 1).to_numpy(zero_copy_only=False)
            columns[name] = texts[codes]
        else:
            columns[name] = column.to_numpy()
    return columns


def dataset_statistics(dataset: Path, pairs, families) -> dict:
    """The statistics of every run in ``dataset``, one engine × preset × family group read at
    a time (rows and bits of :func:`harness.survey.statistics.statistics` of every run);
    ``families``: the populations' names in the survey's order."""
    rows: list[dict] = []
    positions = {family: position for position, family in enumerate(families)}
    for engine, preset in sorted(pairs):
        for family in sorted(families):
            runs = pair_table(dataset, engine, preset, STATISTICS_COLUMNS,
                              [(family, positions[family])])
            if not runs or not len(runs["engine"]):
                continue
            stats = statistics.statistics(runs)
            if stats:
                rows.append(stats)
    if not rows:
        return {}
    return {name: np.concatenate([block[name] for block in rows]) for name in rows[0]}


def figure_runs(dataset: Path, pairs, families) -> dict:
    """The runs the figures draw: the first :data:`FIGURE_SAMPLES` samples of every family,
    every pair, in the order of ``runs.parquet``."""
    placed = [(family, position) for position, family in enumerate(families)]
    blocks = [pair_table(dataset, engine, preset, FIGURE_COLUMNS, placed, FIGURE_SAMPLES)
              for engine, preset in pairs]
    blocks = [block for block in blocks if block]
    if not blocks:
        return {}
    return {name: np.concatenate([block[name] for block in blocks]) for name in FIGURE_COLUMNS}


def concatenate(dataset: Path, pairs, families, path: Path, metadata: dict,
                table: str) -> Path:
    """One Parquet file of a dataset table (``"runs"``: pair after pair, family after family,
    by sample, as the survey held in memory orders them; ``"samples"``: family after family),
    written a chunk file's family at a time into row groups of :data:`ROW_GROUP_ROWS`,
    atomically."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    directories = ([_pair_directory(dataset, engine, preset) for engine, preset in pairs]
                   if table == "runs" else [dataset / "samples"])
    directories = [directory for directory in directories
                   if any(directory.glob("part-*.parquet"))]
    schema = pq.read_schema(next(directories[0].glob("part-*.parquet")))
    temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with pq.ParquetWriter(temporary, schema.with_metadata(
                {outputs.METADATA_KEY: json.dumps({**metadata, "table": table},
                                                  sort_keys=True, default=str)})) as writer:
            pending: list = []  # blocks gathered into row groups of ROW_GROUP_ROWS
            for directory in directories:
                for position, family in enumerate(families):
                    for block in family_blocks(directory, family, position):
                        pending.append(block.cast(writer.schema))
                        if sum(part.num_rows for part in pending) >= ROW_GROUP_ROWS:
                            writer.write_table(pa.concat_tables(pending))
                            pending = []
            if pending:
                writer.write_table(pa.concat_tables(pending))
        if path.is_symlink() or (path.exists() and not path.is_file()):
            raise ValueError(f"{path}: not a regular file; not replaced")
        os.replace(temporary, path)
    finally:
        if temporary.exists():
            temporary.unlink()
    return path
