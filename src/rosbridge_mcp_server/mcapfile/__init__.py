"""An MCAP file read within a budget: whoever wrote it, whatever it declares.

A recording is a file anyone may put in the recordings folder (or a hostile robot may have filled), and MCAP
records carry their own lengths, counts and sizes: a 61 kB file can declare a 2 GB chunk, one message index
can be named by 600 chunk indexes, an 8.9 kB chunk can decompress to millions of tiny records. The ``mcap``
package believes what a file declares; this module does not. It reads the records itself and holds every
declared size, count and offset to the file's real size and to a :class:`Budget` (the memory one call may
hold, the same as a picture's, and the seconds it may take) before it reads, allocates or decompresses:

* each record's length fits in what is left of the file (or of its chunk): a cut-off file is named as such;
* a chunk declares at most the memory budget uncompressed, is decompressed as a stream (never held whole)
  and may not yield more than it declared, nor more records than :data:`RECORDS_PER_COMPRESSED_BYTE` per
  byte of compressed data (beyond :data:`RECORDS_FLOOR`): the work a chunk costs stays in proportion to the
  file;
* every chunk index points inside the file, and no two at the same message index (the fan-out); the
  message times kept at once fit in the memory budget;
* a message's data, a schema's text and a metadata string are capped before they are read;
* a ``ros2msg``/``ros1msg`` schema names no type that contains itself and nests at most :data:`MAX_NESTING`
  levels (:func:`schema_problem`), so no decoder recurses without end, and no array of a type that takes
  no bytes makes billions of objects from a four-byte length; what a message may cost decoded by its schema
  (:func:`decode_cost`) is held to the budget before it is decoded.

Every refusal is a :class:`RecordingProblem` whose text names what is wrong and where. Pure file reading: it
imports nothing of ours, so the simulated robot's ``--play`` holds files to the same rules.
"""

from rosbridge_mcp_server.mcapfile.model import (
    INDEX_ENTRY_COST,
    MAGIC,
    MAX_NESTING,
    Budget,
    Channel,
    ChunkIndex,
    CutOff,
    OverBudget,
    RecordingProblem,
    Schema,
    Statistics,
    Summary,
    byte_size,
)
from rosbridge_mcp_server.mcapfile.reader import McapFile
from rosbridge_mcp_server.mcapfile.schemas import DecodeCost, decode_cost, schema_problem

__all__ = [
    "INDEX_ENTRY_COST",
    "MAGIC",
    "MAX_NESTING",
    "Budget",
    "Channel",
    "ChunkIndex",
    "CutOff",
    "DecodeCost",
    "McapFile",
    "OverBudget",
    "RecordingProblem",
    "Schema",
    "Statistics",
    "Summary",
    "byte_size",
    "decode_cost",
    "schema_problem",
]
