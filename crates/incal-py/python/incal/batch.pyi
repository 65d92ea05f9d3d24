"""Type stubs of incal.batch (see ``batch.py`` for the docs)."""

import os
from typing import Any, Dict, Iterable, List, Optional, Union

from . import Result
from .records import Records

__all__: List[str]

PROCEDURES: Dict[str, str]

class FileError:
    path: str
    message: str
    code: int
    def __init__(self, path: str, message: str, code: int) -> None: ...

class Batch(List[Union[Result, FileError]]):
    paths: List[str]
    record_ids: Optional[List[Optional[int]]]
    stopped: Dict[str, str]
    @property
    def results(self) -> Dict[str, Result]: ...
    @property
    def errors(self) -> Dict[str, FileError]: ...

def reduce(
    paths: Iterable[Union[str, "os.PathLike[str]"]],
    procedure: str,
    client: Any = ...,
    records: Optional[Union[str, "os.PathLike[str]", Records]] = ...,
    serial_from_stem: bool = ...,
    progress: bool = ...,
    units: Optional[Union[str, "os.PathLike[str]", Iterable[str], Dict[str, str]]] = ...,
    unit_column: str = ...,
    **options: Any,
) -> Batch: ...
