"""Material libraries at scale: read, evaluate and grade many files, one file at a time.

The ``report`` materials section and ``eval --jsonl`` share this package:

- :mod:`.files` lists the material files of the given paths (sorted, with each file's path
  relative to the path it was found under);
- :mod:`.worker` does the work of one file (:func:`.worker.process_file`): read it, evaluate
  each material, return compact JSON-ready records, and say which other files the result
  depends on (sublayers, references, payloads, textures, XIncludes);
- :mod:`.cache` keeps those results on disk, keyed on the file, the task, the code and the
  environment, and valid only while the content hashes of the file and of every dependency
  are unchanged;
- :mod:`.pool` runs the files serially, over a pool of worker processes (``jobs``) or on a
  Dask cluster (``scheduler``), and yields the results in the order of the files;
- :mod:`.progress` shows how far it got: a bar on a terminal, else a line every few seconds;
- :mod:`.summary` turns the records into the counts, distributions and the worst materials
  the report shows.

Example
-------
>>> from openpbr_diffuse.library import Task, list_files, run
>>> from openpbr_diffuse.readers import BUNDLED_MATERIALS
>>> files = list_files([BUNDLED_MATERIALS / "clay_rough.mtlx"])
>>> [(r.index, r.payload["records"][0]["material"]) for r in run([(f.path, Task()) for f in files])]
[(0, 'clay_rough')]
"""

from .cache import Cache, default_cache_dir
from .files import LibraryFile, list_files
from .options import PREVIEWS, LibraryOptions
from .pool import Outcome, Runner, run, usable_cores
from .progress import Progress
from .worker import Task, process_file

__all__ = [
    "Cache",
    "LibraryFile",
    "LibraryOptions",
    "Outcome",
    "PREVIEWS",
    "Progress",
    "Runner",
    "Task",
    "default_cache_dir",
    "list_files",
    "process_file",
    "run",
    "usable_cores",
]
