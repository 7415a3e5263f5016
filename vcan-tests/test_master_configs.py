"""The master configurations users copy (examples/), played as their masters play them.

examples/ros2_canopen/ holds a ros2_canopen bus configuration (bus.yml), the stepnode
config it goes with (stepnode.toml) and the node's EDS for that config
(stepnode_cia402.eds). ros2_canopen is not on this machine; what it does with those files
at boot is lely's: its dcfgen turns bus.yml + EDS into a list of SDO writes per slave (the
"concise DCF"), and lely's NMT master plays CiA 302-2's boot-slave procedure with it. The
tests here do the same from the files alone, never from knowledge of the node:

- the EDS is read as dcfgen reads it (an object exists only if [Mandatory/Optional/
  ManufacturerObjects] lists it; $NODEID evaluated) and checked against the rules of
  lely's strict EDS check (dcf-tools lint), which makes dcfgen refuse a file;
- every object bus.yml names must exist in the EDS with a compatible access (an SDO write:
  writable; an RPDO entry: writable and PDO-mappable; a TPDO entry: readable and mappable)
  and type (the value fits the data type and the EDS limits; a mapped object has a bit
  length; at most 64 bits per PDO);
- the write list is built in dcfgen's order: the node's heartbeat consumer for the master
  (1016h, master heartbeat_producer x heartbeat_multiplier) first, its heartbeat producer
  1017h, then per PDO CiA 301's procedure (COB-ID with bit 31 set, transmission type and
  timers while invalid, mapping count 0, the entries, the count, the COB-ID without bit
  31), then bus.yml's `sdo:` list; each is written by SDO with the size of the EDS's data
  type;
- on the bus: the node is started with the committed stepnode.toml; the master checks the
  identity the EDS promises (1000h, 1018h: lely's 1F84h..1F88h), writes the list, starts
  consuming the node's heartbeat (1017h x multiplier), NMT-starts it, produces SYNC at
  sync_period and its own heartbeat; then drives the axis as canopen_402_driver does
  over the PDOs bus.yml configured, with the COB-IDs bus.yml gives ("auto": dcfgen's
  pre-defined set): the CiA 402 state machine to Operation enabled, a CSP move
  streamed one set-point per SYNC, then a PP move with the set-point handshake;
- the EDS the node serves over 1021h, and the one the build prints for stepnode.toml, are
  byte for byte the committed file (so the example cannot go stale).

The CiA 402 words (controlword commands, statusword masks) are cia402_master's, written
from the standard.
"""

from __future__ import annotations

import collections
import copy
import errno
import json
import math
import re
import struct
import subprocess
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

import can
import pytest

try:
    import tomllib
except ImportError:  # Python < 3.11
    tomllib = None

from canopen_master import (
    ABORT_TEXT, STATE_OPERATIONAL, STATE_PREOPERATIONAL, SdoAbort, decode_emcy, decode_heartbeat,
)
from cia402_master import (
    CW_ENABLE_OPERATION, CW_NEW_SET_POINT, CW_SHUTDOWN, CW_SWITCH_ON, MODE_CSP, MODE_PP, OPERATION_ENABLED,
    READY_TO_SWITCH_ON, STATE_TIMEOUT, SW_FOLLOWING_ERROR, SW_SET_POINT_ACK, SW_TARGET_REACHED, SWITCHED_ON, State,
    sw_text,
)
from conftest import REPO_ROOT, open_bus

EXAMPLE = REPO_ROOT / "examples" / "ros2_canopen"
BUS_YML = EXAMPLE / "bus.yml"
NODE_TOML = EXAMPLE / "stepnode.toml"
CIA402_DRIVER = "ros2_canopen::Cia402Driver"

SW_DRIVE_FOLLOWS = 1 << 12  # csp: statusword bit 12 "drive follows the command value"
COB_SYNC = 0x080

# ====================================================================== bus.yml


def load_yaml(path: Path) -> Any:
    """PyYAML (python3-yaml) when installed, else the subset bus.yml files use."""
    text = path.read_text()
    try:
        import yaml
    except ImportError:
        return parse_yaml_subset(text)
    return yaml.safe_load(text)


def _strip_comment(line: str) -> str:
    quote = None
    for i, c in enumerate(line):
        if quote:
            if c == quote:
                quote = None
        elif c in "\"'":
            quote = c
        elif c == "#" and (i == 0 or line[i - 1] in " \t"):
            return line[:i]
    return line


def _split_top(text: str, sep: str) -> List[str]:
    out, depth, quote, cur = [], 0, None, ""
    for c in text:
        if quote:
            quote = None if c == quote else quote
        elif c in "\"'":
            quote = c
        elif c in "{[":
            depth += 1
        elif c in "}]":
            depth -= 1
        elif c == sep and depth == 0:
            out.append(cur)
            cur = ""
            continue
        cur += c
    if cur.strip():
        out.append(cur)
    return out


def _scalar(text: str) -> Any:
    s = text.strip()
    if s.startswith("{") and s.endswith("}"):
        out = {}
        for item in _split_top(s[1:-1], ","):
            k, _, v = item.partition(":")
            out[_scalar(k)] = _scalar(v)
        return out
    if s.startswith("[") and s.endswith("]"):
        return [_scalar(x) for x in _split_top(s[1:-1], ",")]
    if len(s) >= 2 and s[0] == s[-1] and s[0] in "\"'":
        return s[1:-1]
    if s in ("", "~", "null", "Null", "NULL"):
        return None
    if s in ("true", "True", "TRUE"):
        return True
    if s in ("false", "False", "FALSE"):
        return False
    if re.fullmatch(r"[-+]?0x[0-9a-fA-F]+", s):
        return int(s, 16)
    if re.fullmatch(r"[-+]?[0-9]+", s):
        return int(s, 10)
    try:
        return float(s)
    except ValueError:
        return s


def parse_yaml_subset(text: str) -> Any:
    """Block mappings and sequences by indentation, flow mappings/lists, plain and quoted
    scalars, comments: what ros2_canopen's bus.yml files use (no anchors, no multi-line
    strings)."""
    lines = []
    for raw in text.splitlines():
        line = _strip_comment(raw).rstrip()
        if line.strip() and line.strip() != "---":
            lines.append((len(line) - len(line.lstrip(" ")), line.strip()))

    def block(i: int, indent: int) -> Tuple[Any, int]:
        if lines[i][1].startswith("- ") or lines[i][1] == "-":
            seq = []
            while i < len(lines) and lines[i][0] == indent and (lines[i][1].startswith("- ") or lines[i][1] == "-"):
                item = lines[i][1][1:].strip()
                i += 1
                if item:
                    if re.match(r"^[^{\[\"'][^:]*:(\s|$)", item):
                        raise ValueError(f"bus.yml subset parser: a mapping inside a list item: {item!r}")
                    seq.append(_scalar(item))
                elif i < len(lines) and lines[i][0] > indent:
                    value, i = block(i, lines[i][0])
                    seq.append(value)
                else:
                    seq.append(None)
            return seq, i
        mapping: Dict[Any, Any] = {}
        while i < len(lines) and lines[i][0] == indent:
            text_ = lines[i][1]
            if text_.startswith("- "):
                break
            key, sep, rest = text_.partition(":")
            if not sep:
                raise ValueError(f"bus.yml subset parser: not 'key: value': {text_!r}")
            i += 1
            if rest.strip():
                mapping[_scalar(key)] = _scalar(rest)
            elif i < len(lines) and (lines[i][0] > indent or (lines[i][0] == indent and lines[i][1].startswith("-"))):
                mapping[_scalar(key)], i = block(i, lines[i][0])
            else:
                mapping[_scalar(key)] = None
        return mapping, i

    if not lines:
        return None
    value, i = block(0, lines[0][0])
    if i != len(lines):
        raise ValueError(f"bus.yml subset parser: cannot read line {lines[i][1]!r}")
    return value


def cia402_devices(cfg: Dict) -> List[str]:
    """The bus.yml sections of CiA 402 devices (ros2_canopen: every key but options and
    master is a device)."""
    return [k for k, v in cfg.items() if k not in ("options", "master") and isinstance(v, dict)
            and v.get("driver") == CIA402_DRIVER]


def load_toml(path: Path) -> Dict:
    if tomllib is None:
        pytest.skip("tomllib needs Python 3.11")
    with open(path, "rb") as f:
        return tomllib.load(f)


# ====================================================================== EDS (CiA 306)

# CiA 301 data types: name, bits, struct code (None: no integer encoding here), min, max
TYPES = {
    0x0001: ("BOOLEAN", 1, "B", 0, 1),
    0x0002: ("INTEGER8", 8, "b", -0x80, 0x7F),
    0x0003: ("INTEGER16", 16, "h", -0x8000, 0x7FFF),
    0x0004: ("INTEGER32", 32, "i", -0x80000000, 0x7FFFFFFF),
    0x0005: ("UNSIGNED8", 8, "B", 0, 0xFF),
    0x0006: ("UNSIGNED16", 16, "H", 0, 0xFFFF),
    0x0007: ("UNSIGNED32", 32, "I", 0, 0xFFFFFFFF),
    0x0008: ("REAL32", 32, None, None, None),
    0x0010: ("INTEGER24", 24, None, -0x800000, 0x7FFFFF),
    0x0011: ("REAL64", 64, None, None, None),
    0x0012: ("INTEGER40", 40, None, -(1 << 39), (1 << 39) - 1),
    0x0013: ("INTEGER48", 48, None, -(1 << 47), (1 << 47) - 1),
    0x0014: ("INTEGER56", 56, None, -(1 << 55), (1 << 55) - 1),
    0x0015: ("INTEGER64", 64, "q", -(1 << 63), (1 << 63) - 1),
    0x0016: ("UNSIGNED24", 24, None, 0, 0xFFFFFF),
    0x0018: ("UNSIGNED40", 40, None, 0, (1 << 40) - 1),
    0x0019: ("UNSIGNED48", 48, None, 0, (1 << 48) - 1),
    0x001A: ("UNSIGNED56", 56, None, 0, (1 << 56) - 1),
    0x001B: ("UNSIGNED64", 64, "Q", 0, (1 << 64) - 1),
}
STRING_TYPES = {0x0009, 0x000A, 0x000B, 0x000C, 0x000D, 0x000F}  # strings, times, DOMAIN: no PDO bits here
ACCESS = {"ro", "wo", "rw", "rwr", "rww", "const"}
WRITABLE = {"wo", "rw", "rwr", "rww"}
RPDO_ACCESS = {"wo", "rw", "rww"}  # CiA 306: rww = read/write, mappable into RPDOs
TPDO_ACCESS = {"ro", "const", "rw", "rwr"}  # rwr = read/write, mappable into TPDOs
VALUE_RE = re.compile(r"\s*(\$(?P<var>NODEID)\s*\+\s*)?(?P<value>-?0x[0-9A-F]+|-?[0-9]+)\s*$", re.IGNORECASE)


def parse_value(text: str, node_id: Optional[int]) -> int:
    m = VALUE_RE.match(text)
    if not m:
        raise ValueError(f"not an integer value: {text!r}")
    value = int(m.group("value"), 0)
    if m.group("var"):
        if node_id is None:
            raise ValueError(f"{text!r} needs $NODEID")
        value += node_id
    return value


class Eds:
    """An EDS as lely's dcf-tools read one: sections by name (upper case), entries by key
    (lower case); an object exists when an object list names it."""

    def __init__(self, text: str, name: str = "EDS"):
        self.name = name
        self.text = text
        self.sections: Dict[str, Dict[str, str]] = {}
        self.section_names: List[str] = []
        self.syntax: List[str] = []
        cur = None
        for n, line in enumerate(text.splitlines(), 1):
            s = line.strip()
            if not s or s.startswith(";"):
                continue
            if s.startswith("[") and s.endswith("]"):
                cur = s[1:-1].strip()
                if cur.upper() in self.sections:
                    self.syntax.append(f"line {n}: section [{cur}] appears twice")
                self.sections[cur.upper()] = {}
                self.section_names.append(cur)
            elif "=" in s and cur is not None:
                k, v = s.split("=", 1)
                self.sections[cur.upper()][k.strip().lower()] = v.strip()
            else:
                self.syntax.append(f"line {n}: neither [section] nor key=value: {s!r}")
        self.listed: Dict[int, str] = {}
        for lst in ("MANDATORYOBJECTS", "OPTIONALOBJECTS", "MANUFACTUREROBJECTS"):
            sec = self.sections.get(lst, {})
            for i in range(1, int(sec.get("supportedobjects", "0"), 10) + 1):
                try:
                    self.listed[int(sec.get(str(i), ""), 0)] = lst
                except ValueError:
                    pass

    @classmethod
    def from_file(cls, path: Path) -> "Eds":
        return cls(path.read_text(errors="replace"), path.name)

    def info(self, key: str) -> str:
        return self.sections.get("DEVICEINFO", {}).get(key.lower(), "")

    def entry(self, index: int, sub: int) -> Optional[Dict[str, str]]:
        """The section describing index:sub, None if dcfgen would not find it."""
        if index not in self.listed:
            return None
        obj = self.sections.get(f"{index:04X}")
        if obj is None:
            return None
        if int(obj.get("subnumber", "0"), 0):
            return self.sections.get(f"{index:04X}SUB{sub:X}")
        return obj if sub == 0 else None

    def dtype(self, index: int, sub: int) -> int:
        return int(self.entry(index, sub)["datatype"], 0)

    def default(self, index: int, sub: int, node_id: Optional[int]) -> int:
        e = self.entry(index, sub)
        return parse_value(e.get("parametervalue", e.get("defaultvalue", "0")) or "0", node_id)

    def limits(self, index: int, sub: int, node_id: Optional[int]) -> Tuple[int, int]:
        e = self.entry(index, sub)
        _, _, _, lo, hi = TYPES[int(e["datatype"], 0)]
        if e.get("lowlimit"):
            lo = parse_value(e["lowlimit"], node_id)
        if e.get("highlimit"):
            hi = parse_value(e["highlimit"], node_id)
        return lo, hi

    def mapping(self, index: int, node_id: int) -> List[Tuple[int, int, int]]:
        """The (index, sub, bits) entries of a PDO mapping record's defaults."""
        out = []
        for k in range(1, self.default(index, 0, node_id) + 1):
            if self.entry(index, k) is not None and (v := self.default(index, k, node_id)):
                out.append((v >> 16, v >> 8 & 0xFF, v & 0xFF))
        return out


# ------------------------------------------------------------------ lely's strict EDS check

FILEINFO_KEYS = {k.lower() for k in ("FileName", "FileVersion", "FileRevision", "EDSVersion", "Description",
                                     "CreationTime", "CreationDate", "CreatedBy", "ModificationTime",
                                     "ModificationDate", "ModifiedBy")}
DEVICEINFO_KEYS = {k.lower() for k in ("VendorName", "VendorNumber", "ProductName", "ProductNumber", "RevisionNumber",
                                       "OrderCode", "BaudRate_10", "BaudRate_20", "BaudRate_50", "BaudRate_125",
                                       "BaudRate_250", "BaudRate_500", "BaudRate_800", "BaudRate_1000",
                                       "SimpleBootUpMaster", "SimpleBootUpSlave", "Granularity",
                                       "DynamicChannelsSupported", "GroupMessaging", "NrOfRxPDO", "NrOfTxPDO",
                                       "LSS_Supported", "CompactPDO")}
COMMISSIONING_KEYS = {k.lower() for k in ("NodeID", "NodeName", "NodeRefd", "Baudrate", "NetNumber", "NetworkName",
                                          "NetRefd", "CANopenManager", "LSS_SerialNumber")}
OBJECT_KEYS = {k.lower() for k in ("SubNumber", "ParameterName", "ObjectType", "DataType", "AccessType", "LowLimit",
                                   "HighLimit", "DefaultValue", "PDOMapping", "ObjFlags", "CompactSubObj",
                                   "ParameterValue", "UploadFile", "DownloadFile", "Denotation", "ParamRefd")}
OBJECT_SECTION = re.compile(r"([0-9A-F]{4})(NAME|VALUE|SUB([0-9A-F]+))?$")


def lint_eds(eds: Eds) -> List[str]:
    """The checks lely's dcf-tools make before dcfgen uses an EDS (strict mode refuses the
    file on any of them), restated from its rules: known sections and keys, complete
    object lists, SubNumber = the sub-objects present, sub-index 0 UNSIGNED8, a known
    data type and access type, default values and limits within the data type."""
    out = list(eds.syntax)
    known = {"FILEINFO": FILEINFO_KEYS, "DEVICEINFO": DEVICEINFO_KEYS, "DEVICECOMISSIONING": COMMISSIONING_KEYS}
    for name in eds.section_names:
        sec, up = eds.sections[name.upper()], name.upper()
        if up in known:
            out += [f"[{name}]: unknown entry {k}" for k in sec if k not in known[up]]
        elif up in ("COMMENTS", "DUMMYUSAGE"):
            continue
        elif up in ("MANDATORYOBJECTS", "OPTIONALOBJECTS", "MANUFACTUREROBJECTS"):
            if "supportedobjects" not in sec:
                out.append(f"[{name}]: no SupportedObjects")
                continue
            n = int(sec["supportedobjects"], 10)
            if len(sec) - 1 > n:
                out.append(f"[{name}]: more entries than SupportedObjects={n}")
            for i in range(1, n + 1):
                if str(i) not in sec:
                    out.append(f"[{name}]: entry {i} missing")
                    continue
                index = int(sec[str(i)], 0)
                if f"{index:04X}" not in eds.sections:
                    out.append(f"[{name}] {i}=0x{index:04X}: no section [{index:04X}]")
                if up == "MANDATORYOBJECTS" and index not in (0x1000, 0x1001, 0x1018):
                    out.append(f"[{name}]: 0x{index:04X} is not a mandatory object")
                if up == "OPTIONALOBJECTS" and not (0x1000 <= index < 0x2000 or index >= 0x6000):
                    out.append(f"[{name}]: 0x{index:04X} is manufacturer-specific")
                if up == "MANUFACTUREROBJECTS" and not 0x2000 <= index < 0x6000:
                    out.append(f"[{name}]: 0x{index:04X} is not manufacturer-specific")
        elif m := OBJECT_SECTION.match(up):
            index = int(m.group(1), 16)
            out += [f"[{name}]: unknown entry {k}" for k in sec if k not in OBJECT_KEYS]
            if "parametername" not in sec and not m.group(2) in ("NAME", "VALUE"):
                out.append(f"[{name}]: no ParameterName")
            if m.group(2) is None:
                subs = [s for s in range(255) if f"{index:04X}SUB{s:X}" in eds.sections]
                n = int(sec.get("subnumber", "0"), 0)
                if n:
                    if int(sec.get("objecttype", "0"), 0) not in (8, 9):
                        out.append(f"[{name}]: SubNumber with ObjectType {sec.get('objecttype')}")
                    if len(subs) != n:
                        out.append(f"[{name}]: SubNumber={n}, {len(subs)} sub-objects")
                    if 0 in subs and int(eds.sections[f"{index:04X}SUB0"].get("datatype", "0"), 0) != 0x0005:
                        out.append(f"[{name}sub0]: not UNSIGNED8")
                else:
                    out += _lint_var(name, sec)
            elif m.group(3) is not None:
                if f"{index:04X}" not in eds.sections:
                    out.append(f"[{name}]: no object section [{index:04X}]")
                out += _lint_var(name, sec)
        else:
            out.append(f"[{name}]: unknown section")
    return out


def _lint_var(name: str, sec: Dict[str, str]) -> List[str]:
    out = []
    if sec.get("accesstype", "").lower() not in ACCESS:
        out.append(f"[{name}]: AccessType {sec.get('accesstype')!r}")
    try:
        dt = int(sec.get("datatype", ""), 0)
    except ValueError:
        return out + [f"[{name}]: DataType {sec.get('datatype')!r}"]
    if dt in STRING_TYPES:
        if sec.get("lowlimit") or sec.get("highlimit"):
            out.append(f"[{name}]: limits on a string/DOMAIN")
        return out
    if dt not in TYPES:
        return out + [f"[{name}]: unsupported DataType 0x{dt:04X}"]
    _, _, _, lo, hi = TYPES[dt]
    if lo is None:
        return out  # REAL32/REAL64: not checked here

    def number(key):
        m = VALUE_RE.match(sec[key])
        if not m:
            out.append(f"[{name}]: {key} {sec[key]!r} is not an integer")
            return None, False
        return int(m.group("value"), 0), m.group("var") is not None

    # Limits within the data type; a value within the limits ($NODEID+x: x leaves room
    # for node-IDs 1..127).
    vlo, vhi = lo, hi
    for key in ("lowlimit", "highlimit"):
        if sec.get(key):
            v, _ = number(key)
            if v is not None and not lo <= v <= hi:
                out.append(f"[{name}]: {key}={sec[key]} outside {TYPES[dt][0]}")
            elif v is not None:
                vlo, vhi = (v, vhi) if key == "lowlimit" else (vlo, v)
    for key in ("defaultvalue", "parametervalue"):
        if sec.get(key):
            v, nodeid = number(key)
            if v is not None and not vlo - nodeid <= v <= vhi - 127 * nodeid:
                out.append(f"[{name}]: {key}={sec[key]} outside {vlo}..{vhi}")
    return out


# ====================================================================== the boot plan (dcfgen)


@dataclass
class Write:
    index: int
    sub: int
    value: int
    why: str

    def __repr__(self):
        return f"0x{self.index:04X}:{self.sub} = {self.value:#x} ({self.why})"


@dataclass
class Pdo:
    kind: str  # "rpdo" (the node receives) or "tpdo" (the node sends)
    number: int
    cob_id: int  # as bus.yml makes it (bit 31 set: invalid)
    transmission: int
    mapping: List[Tuple[int, int, int]]  # (index, sub, bits)
    fmt: str = ""  # struct format of the payload, from the EDS data types

    @property
    def valid(self) -> bool:
        return not self.cob_id & 0x80000000

    @property
    def can_id(self) -> int:
        return self.cob_id & 0x7FF

    @property
    def synchronous(self) -> bool:
        return self.transmission <= 240

    def carries(self, index: int, sub: int = 0) -> bool:
        return any(m[0] == index and m[1] == sub for m in self.mapping)

    def pack(self, values: Dict[Tuple[int, int], int]) -> bytes:
        return struct.pack(self.fmt, *(values.get((i, s), 0) for i, s, _ in self.mapping))

    def unpack(self, data: bytes) -> Dict[Tuple[int, int], int]:
        return dict(zip(((i, s) for i, s, _ in self.mapping), struct.unpack(self.fmt, data)))


@dataclass
class BootPlan:
    device: str
    node_id: int
    master_id: int
    writes: List[Write] = field(default_factory=list)
    pdos: Dict[Tuple[str, int], Pdo] = field(default_factory=dict)
    identity: List[Tuple[int, int, int, str]] = field(default_factory=list)  # index, sub, expected, what
    problems: List[str] = field(default_factory=list)
    sync_period_us: int = 0
    node_consumer_ms: int = 0  # the node waits this long for the master's heartbeat (1016h)
    node_heartbeat_ms: int = 0  # the node's producer time (1017h)
    master_consumer_ms: int = 0  # the master waits this long for the node's heartbeat

    def pdo_with(self, kind: str, index: int, sub: int = 0) -> Pdo:
        found = [p for (k, _), p in sorted(self.pdos.items()) if k == kind and p.valid and p.carries(index, sub)]
        assert found, f"bus.yml maps 0x{index:04X}:{sub} into no enabled {kind}"
        return found[0]

    def sdo_value(self, index: int, sub: int = 0) -> Optional[int]:
        """The value the boot writes last to index:sub (None: not written)."""
        v = None
        for w in self.writes:
            if (w.index, w.sub) == (index, sub):
                v = w.value
        return v

    def concise_dcf_lines(self, eds: Eds) -> List[str]:
        """dcfgen -v's lines: '<name>: writing N bytes to 0xIIII/S: HEX'."""
        out = []
        for w in self.writes:
            try:
                data = encode(eds, w.index, w.sub, w.value)
                out.append(f"{self.device}: writing {len(data)} bytes to 0x{w.index:04X}/{w.sub}: {data.hex().upper()}")
            except (ValueError, KeyError, struct.error, TypeError) as e:
                out.append(f"{self.device}: cannot encode {w!r}: {e}")
        return out


def encode(eds: Eds, index: int, sub: int, value: int) -> bytes:
    """The value in the size of the object's data type (what dcfgen's concise DCF holds)."""
    name, bits, code, _, _ = TYPES[eds.dtype(index, sub)]
    if code is None:
        raise ValueError(f"0x{index:04X}:{sub}: {name} not encoded by this test")
    return struct.pack("<" + code, value)


def build_plan(cfg: Dict, device: str, eds: Eds) -> BootPlan:
    """The SDO writes lely's dcfgen derives from bus.yml for `device`, in its order, with
    every object bus.yml names checked against the EDS."""
    options = cfg.get("options") or {}
    master = cfg.get("master") or {}
    dev = cfg[device]
    multiplier = float(options.get("heartbeat_multiplier", 3.0))
    node_id = int(dev.get("node_id", 255))
    plan = BootPlan(device, node_id, int(master.get("node_id", 255)))
    p = plan.problems
    if not 1 <= node_id <= 127:
        p.append(f"{device}: node_id {node_id} is not 1..127")
        return plan
    plan.sync_period_us = int(master.get("sync_period", 0))
    cob_pool = [0x680]

    def check_write(index: int, sub: int, value: Any, why: str) -> Optional[Write]:
        where = f"{device}: {why}: 0x{index:04X}:{sub}"
        e = eds.entry(index, sub)
        if e is None:
            p.append(f"{where}: not in {eds.name}" + ("" if index not in eds.listed else " (no such sub-index)"))
            return None
        if e.get("accesstype", "").lower() not in WRITABLE:
            p.append(f"{where}: AccessType {e.get('accesstype')} in {eds.name}: not writable")
        dt = int(e.get("datatype", "0"), 0)
        if dt not in TYPES or TYPES[dt][3] is None:
            p.append(f"{where}: DataType 0x{dt:04X} takes no integer")
            return None
        if isinstance(value, bool) or not isinstance(value, int):
            p.append(f"{where}: value {value!r} is not an integer")
            return None
        lo, hi = eds.limits(index, sub, node_id)
        if not lo <= value <= hi:
            p.append(f"{where}: value {value} outside {TYPES[dt][0]} {lo}..{hi} ({eds.name})")
            return None
        return Write(index, sub, value, why)

    def write(index: int, sub: int, value: Any, why: str) -> None:
        w = check_write(index, sub, value, why)
        if w is not None:
            plan.writes.append(w)

    # The master's identity checks at boot (lely: 1F84h..1F88h from the EDS; bus.yml may
    # give revision_number and serial_number, 0 = not checked).
    def ident(index, sub, value, what):
        if value:
            plan.identity.append((index, sub, value, what))

    try:
        ident(0x1000, 0, eds.default(0x1000, 0, node_id), "device type (1F84h)")
        vendor = int(eds.info("VendorNumber"), 0) if eds.info("VendorNumber") else eds.default(0x1018, 1, node_id)
        ident(0x1018, 1, vendor, "vendor-ID (1F85h)")
        product = int(eds.info("ProductNumber"), 0) if eds.info("ProductNumber") else eds.default(0x1018, 2, node_id)
        ident(0x1018, 2, product, "product code (1F86h)")
        revision = int(eds.info("RevisionNumber"), 0) if eds.info("RevisionNumber") else eds.default(0x1018, 3, node_id)
        ident(0x1018, 3, int(dev.get("revision_number", revision)), "revision number (1F87h)")
        ident(0x1018, 4, int(dev.get("serial_number", eds.default(0x1018, 4, node_id))), "serial number (1F88h)")
    except (TypeError, KeyError, ValueError) as e:
        p.append(f"{device}: identity objects 1000h/1018h unreadable in {eds.name}: {e}")

    # heartbeat_producer -> 1017h (written when it differs from the EDS).
    if "heartbeat_producer" in dev:
        plan.node_heartbeat_ms = int(dev["heartbeat_producer"])
        if eds.entry(0x1017, 0) is None:
            p.append(f"{device}: heartbeat_producer, but {eds.name} has no 0x1017")
        elif eds.default(0x1017, 0, node_id) != plan.node_heartbeat_ms:
            write(0x1017, 0, plan.node_heartbeat_ms, "heartbeat_producer")
    plan.master_consumer_ms = int(plan.node_heartbeat_ms * float(dev.get("heartbeat_multiplier", multiplier)))

    # error_behavior -> 1029h
    for sub, value in (dev.get("error_behavior") or {}).items():
        if eds.entry(0x1029, int(sub)) is None:
            p.append(f"{device}: error_behavior {sub}: no 0x1029:{sub}")
        elif eds.default(0x1029, int(sub), node_id) != int(value):
            write(0x1029, int(sub), int(value), "error_behavior")

    # PDOs (CiA 301: change a PDO while it is invalid; remap with count 0 first).
    for kind, base in (("rpdo", 0x1400), ("tpdo", 0x1800)):
        n_eds = int(eds.info("NrOfRxPDO" if kind == "rpdo" else "NrOfTxPDO") or "0", 0)
        for number, pcfg in sorted((dev.get(kind) or {}).items()):
            number = int(number)
            pcfg = pcfg or {}
            comm, mapi = base + number - 1, base + 0x200 + number - 1
            what = f"{kind} {number}"
            if eds.entry(comm, 1) is None or eds.entry(mapi, 0) is None:
                p.append(f"{device}: {what}: {eds.name} has no 0x{comm:04X}/0x{mapi:04X} "
                         f"(NrOf{kind[0].upper()}xPDO={n_eds})")
                continue
            is_tpdo = kind == "tpdo"
            cob0 = eds.default(comm, 1, node_id)
            cob = cob0
            if "cob_id" in pcfg:
                if pcfg["cob_id"] == "auto":
                    i = comm & 0x1FF
                    if i < 4:  # CiA 301's pre-defined connection set
                        cob = (i + 1) * 0x100 + (0x80 if is_tpdo else 0x100) + node_id
                    else:
                        cob = cob_pool[0]
                        cob_pool[0] += 1
                else:
                    cob = int(pcfg["cob_id"])
            if cob0 != cob | 0x80000000:
                write(comm, 1, cob | 0x80000000, f"{what} COB-ID invalid (bit 31)")
            transmission = eds.default(comm, 2, node_id)
            mapping = eds.mapping(mapi, node_id)
            enabled = False
            if not cob & 0x80000000:
                if "transmission" in pcfg and int(pcfg["transmission"]) != transmission:
                    transmission = int(pcfg["transmission"])
                    write(comm, 2, transmission, f"{what} transmission type")
                for key, sub, who in (("inhibit_time", 3, "tpdo"), ("event_timer", 5, "tpdo"),
                                      ("event_deadline", 5, "rpdo"), ("sync_start", 6, "tpdo")):
                    if key in pcfg and kind == who and eds.entry(comm, sub) is not None \
                            and int(pcfg[key]) != eds.default(comm, sub, node_id):
                        write(comm, sub, int(pcfg[key]), f"{what} {key}")
                    elif key in pcfg and kind == who and eds.entry(comm, sub) is None:
                        p.append(f"{device}: {what} {key}: no 0x{comm:04X}:{sub} in {eds.name}")
                if "mapping" in pcfg:
                    if mapping:
                        write(mapi, 0, 0, f"{what} mapping count 0")
                    mapping = []
                    for k, m in enumerate(pcfg["mapping"] or [], 1):
                        index, sub = int(m["index"]), int(m.get("sub_index", 0))
                        where = f"{device}: {what} mapping {k}: 0x{index:04X}:{sub}"
                        e = eds.entry(index, sub)
                        if e is None:
                            p.append(f"{where}: not in {eds.name}")
                            continue
                        access = e.get("accesstype", "").lower()
                        if access not in (TPDO_ACCESS if is_tpdo else RPDO_ACCESS):
                            p.append(f"{where}: AccessType {access} cannot be mapped into a "
                                     f"{'TPDO' if is_tpdo else 'RPDO'}")
                        if e.get("pdomapping", "0").strip() not in ("1",):
                            p.append(f"{where}: PDOMapping={e.get('pdomapping', '0')} in {eds.name}")
                        dt = int(e.get("datatype", "0"), 0)
                        if dt not in TYPES:
                            p.append(f"{where}: DataType 0x{dt:04X} has no PDO bit length")
                            continue
                        bits = TYPES[dt][1]
                        mapping.append((index, sub, bits))
                        write(mapi, k, index << 16 | sub << 8 | bits, f"{what} mapping {k}")
                    if sum(b for _, _, b in mapping) > 64:
                        p.append(f"{device}: {what}: {sum(b for _, _, b in mapping)} bits mapped, more than 64")
                    if mapping:
                        write(mapi, 0, len(mapping), f"{what} mapping count")
                enabled = bool(pcfg.get("enabled", True))
                if enabled:
                    write(comm, 1, cob, f"{what} COB-ID valid")
            codes = []
            for i, s, _ in mapping:
                dt = eds.dtype(i, s) if eds.entry(i, s) else 0
                codes.append(TYPES.get(dt, (None, 0, None))[2] or "?")
            pdo = Pdo(kind, number, cob if enabled else cob | 0x80000000, transmission, mapping, "<" + "".join(codes))
            if "?" in pdo.fmt and enabled:
                p.append(f"{device}: {what}: a mapped data type this test cannot encode ({pdo.fmt})")
            plan.pdos[(kind, number)] = pdo

    # bus.yml's own SDO list, last.
    for k, s in enumerate(dev.get("sdo") or [], 1):
        write(int(s["index"]), int(s.get("sub_index", 0)), s.get("value", 0), f"sdo {k}")

    # The master's heartbeat: the node consumes it (dcfgen puts this write first).
    plan.node_consumer_ms = int(float(master.get("heartbeat_producer", 0))
                                   * float(master.get("heartbeat_multiplier", multiplier)))
    if dev.get("heartbeat_consumer") and plan.node_consumer_ms > 0:
        if eds.entry(0x1016, 0) is None:
            p.append(f"{device}: heartbeat_consumer, but {eds.name} has no 0x1016")
        else:
            subs = [s for s in range(1, 128) if eds.entry(0x1016, s) is not None]
            values = {s: eds.default(0x1016, s, node_id) for s in subs}
            pick = [s for s in subs if values[s] >> 16 & 0xFF == plan.master_id] \
                or [s for s in subs if values[s] & 0xFFFF == 0 or not 1 <= values[s] >> 16 & 0xFF <= 127]
            if not pick:
                p.append(f"{device}: no unused entry in 0x1016 for the master's heartbeat")
            else:
                w = check_write(0x1016, pick[0], plan.master_id << 16 | plan.node_consumer_ms & 0xFFFF,
                                "heartbeat_consumer (master heartbeat_producer x multiplier)")
                if w:
                    plan.writes.insert(0, w)
    return plan


def consistency(cfg: Dict, device: str, plan: BootPlan, eds: Eds, node_cfg: Dict) -> List[str]:
    """What makes the example a working CiA 402 CSP/PP set-up, from the files."""
    out = []
    dev, master = cfg[device], cfg.get("master") or {}
    if node_cfg.get("node_id") != plan.node_id:
        out.append(f"stepnode.toml node_id {node_cfg.get('node_id')} != bus.yml {device} node_id {plan.node_id}")
    if "cia402" not in (node_cfg.get("profiles") or []):
        out.append("stepnode.toml: profiles has no \"cia402\"")
    if dev.get("package") != "canopen_402_driver":
        out.append(f"{device}: package {dev.get('package')!r}, ros2_canopen's {CIA402_DRIVER} is in canopen_402_driver")
    if master.get("driver") != "ros2_canopen::MasterDriver" or master.get("package") != "canopen_master_driver":
        out.append("master: driver/package are not ros2_canopen's MasterDriver/canopen_master_driver")
    if eds.default(0x1000, 0, plan.node_id) & 0xFFFF != 402:
        out.append(f"{eds.name}: 1000h = 0x{eds.default(0x1000, 0, plan.node_id):08X}, not a CiA 402 device")
    if plan.sync_period_us <= 0:
        out.append("master: no sync_period (the cyclic modes need SYNC)")
    value, index = plan.sdo_value(0x60C2, 1), plan.sdo_value(0x60C2, 2)
    value = eds.default(0x60C2, 1, plan.node_id) if value is None else value
    index = eds.default(0x60C2, 2, plan.node_id) if index is None else index
    if abs(value * 10.0 ** index * 1e6 - plan.sync_period_us) > 0.5:
        out.append(f"60C2h interpolation time period {value} x 10^{index} s != sync_period {plan.sync_period_us} us")
    if "period" in dev and int(dev["period"]) * 1000 != plan.sync_period_us:
        out.append(f"{device}: period {dev['period']} ms != sync_period {plan.sync_period_us} us")
    mode = plan.sdo_value(0x6060)
    supported = eds.default(0x6502, 0, plan.node_id)
    if mode is not None and mode > 0 and not supported >> (mode - 1) & 1:
        out.append(f"sdo 6060h = {mode}: not in 6502h supported drive modes 0x{supported:X}")
    if mode in (7, 8, 9):
        target = 0x60C1 if mode == 7 else 0x607A if mode == 8 else 0x60FF
        pdo = plan.pdo_with("rpdo", target)
        if not pdo.synchronous:
            out.append(f"mode {mode}: the RPDO with 0x{target:04X} has transmission {pdo.transmission}, "
                       "not synchronous")
    for index in (0x6040, 0x6060, 0x607A):
        if not any(p.valid and p.carries(index) for (k, _), p in plan.pdos.items() if k == "rpdo"):
            out.append(f"no enabled RPDO carries 0x{index:04X}")
    for index in (0x6041, 0x6061, 0x6064):
        if not any(p.valid and p.carries(index) for (k, _), p in plan.pdos.items() if k == "tpdo"):
            out.append(f"no enabled TPDO carries 0x{index:04X}")
    ids = [p.can_id for p in plan.pdos.values() if p.valid]
    if len(ids) != len(set(ids)):
        out.append(f"two PDOs share a COB-ID: {[hex(i) for i in ids]}")
    if dev.get("heartbeat_consumer") and not plan.node_consumer_ms:
        out.append("heartbeat_consumer: true, but the master produces no heartbeat (master heartbeat_producer)")
    if not plan.node_heartbeat_ms:
        out.append(f"{device}: no heartbeat_producer: the master cannot watch the node")
    return out


# ---------------------------------------------------------------- fixtures: the example's files


@pytest.fixture(scope="module")
def example():
    cfg = load_yaml(BUS_YML)
    devices = cia402_devices(cfg)
    assert len(devices) == 1, f"{BUS_YML}: expected one {CIA402_DRIVER} device, found {devices}"
    dev = cfg[devices[0]]
    eds_path = EXAMPLE / str(dev["dcf"])
    assert eds_path.is_file(), f"bus.yml dcf {dev['dcf']!r}: no file {eds_path}"
    eds = Eds.from_file(eds_path)
    plan = build_plan(cfg, devices[0], eds)
    return cfg, devices[0], eds, plan, load_toml(NODE_TOML), eds_path


# ====================================================================== the files alone


def test_bus_yml_names_only_what_the_eds_has(example):
    cfg, device, eds, plan, node_cfg, eds_path = example
    print("\n".join(plan.concise_dcf_lines(eds)))
    lint = lint_eds(eds)
    assert not lint, f"{eds_path.name} fails lely's strict EDS check (dcfgen would refuse it):\n" + "\n".join(lint[:40])
    assert not plan.problems, "bus.yml does not fit the EDS:\n" + "\n".join(plan.problems)
    bad = consistency(cfg, device, plan, eds, node_cfg)
    assert not bad, "the example does not hold together:\n" + "\n".join(bad)
    # Every write can be encoded in the size of its data type (the concise DCF).
    for w in plan.writes:
        encode(eds, w.index, w.sub, w.value)
    # What the test on the bus relies on.
    assert plan.writes and plan.pdos and plan.identity


def test_checker_refuses_broken_copies(example):
    """The checks above can fail: each broken copy of bus.yml is caught, naming the object."""
    cfg, device, eds, _, node_cfg, _ = example

    def problems(mutate: Callable[[Dict], None]) -> str:
        c = copy.deepcopy(cfg)
        mutate(c[device])
        plan = build_plan(c, device, eds)
        return "\n".join(plan.problems + (consistency(c, device, plan, eds, node_cfg) if not plan.problems else []))

    def sdo(index, sub, value):
        return lambda d: d["sdo"].append({"index": index, "sub_index": sub, "value": value})

    def rpdo_map(n, index, sub=0):
        return lambda d: d["rpdo"][n]["mapping"].append({"index": index, "sub_index": sub})

    def set_(key, value):
        return lambda d: d.__setitem__(key, value)

    cases = {
        "an object the EDS lacks": (sdo(0x6FFE, 0, 1), "0x6FFE:0"),
        "a sub-index the EDS lacks": (sdo(0x60C2, 3, 1), "0x60C2:3"),
        "a read-only object": (sdo(0x6041, 0, 0), "0x6041:0"),
        "a value beyond the data type": (sdo(0x60C2, 1, 256), "0x60C2:1"),
        "a value beyond the EDS limits": (sdo(0x605A, 0, 9), "0x605A:0"),
        "a read-only object in an RPDO": (rpdo_map(1, 0x6041), "0x6041:0"),
        "an unmappable object in an RPDO": (rpdo_map(1, 0x6083), "0x6083:0"),
        "more than 64 bits": (rpdo_map(2, 0x60B0), "more than 64"),
        "a PDO the node has not": (lambda d: d["rpdo"].__setitem__(9, {"enabled": True, "mapping": []}), "rpdo 9"),
        "an interpolation period that is not the SYNC period": (sdo(0x60C2, 1, 20), "60C2h"),
        "a mode the drive lacks": (sdo(0x6060, 0, 4), "6060h = 4"),
        "another node id": (set_("node_id", 6), "node_id"),
    }
    missed = []
    for what, (mutate, must) in cases.items():
        text = problems(mutate)
        print(f"{what}: {text.splitlines()[:1]}")
        if must not in text:
            missed.append(f"{what}: expected a problem naming {must!r}, got {text!r}")
    assert not missed, "\n".join(missed)


def test_yaml_subset_parser_reads_bus_yml_as_pyyaml_does():
    try:
        import yaml
    except ImportError:
        pytest.skip("python3-yaml not installed: the subset parser is what reads bus.yml here")
    text = BUS_YML.read_text()
    assert parse_yaml_subset(text) == yaml.safe_load(text)


def test_committed_eds_is_what_the_build_prints_for_stepnode_toml(example, stepnode_bin):
    _, _, _, _, _, eds_path = example
    printed = subprocess.run([str(stepnode_bin), "--print-eds", "--config", str(NODE_TOML)], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, timeout=60)
    assert printed.returncode == 0, printed.stderr.decode(errors="replace")
    assert_same_eds(printed.stdout.decode(errors="replace"), eds_path, "`stepnode --print-eds --config stepnode.toml`")


def assert_same_eds(text: str, committed: Path, source: str) -> None:
    want = committed.read_text(errors="replace")
    if text == want:
        return
    a, b = want.splitlines(), text.splitlines()
    diff = [f"line {i + 1}: committed {x!r} vs {y!r}" for i, (x, y) in enumerate(zip(a, b)) if x != y][:12]
    if len(a) != len(b):
        diff.append(f"{len(a)} lines committed, {len(b)} from {source}")
    pytest.fail(f"{committed.relative_to(REPO_ROOT)} is stale: {source} differs\n" + "\n".join(diff) +
                f"\nregenerate: build/node/stepnode --print-eds --config {NODE_TOML.relative_to(REPO_ROOT)} > "
                f"{committed.relative_to(REPO_ROOT)}", pytrace=False)


# ====================================================================== on the bus


class MasterCycle:
    """The master's periodic frames on a socket of its own, as lely's master sends them:
    its heartbeat every heartbeat period, and every sync_period the synchronous RPDOs of
    the node (their values from the master's copy of the node's objects; a set-point queue
    gives one value per cycle) followed by the SYNC (080h, no counter: 1019h = 0). Absolute
    deadlines, as a timer-driven producer keeps them; a late cycle is sent at once and the
    next one comes no sooner than 3/4 of a period after it (no bursts)."""

    def __init__(self, master_id: int, sync_period: float, heartbeat_period: float, mirror: "Mirror"):
        self.master_id = master_id
        self.sync_period = sync_period
        self.heartbeat_period = heartbeat_period
        self.mirror = mirror
        self.state = STATE_PREOPERATIONAL
        self.sync_rpdos: List[Pdo] = []
        self.queue: Dict[Tuple[int, int], collections.deque] = {}
        self.cycles = 0
        self.slips = 0
        self.errors: List[str] = []
        self._bus = open_bus()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def stream(self, index: int, values: Sequence[int], sub: int = 0) -> None:
        with self.mirror.lock:
            self.queue.setdefault((index, sub), collections.deque()).extend(values)

    def pending(self) -> int:
        with self.mirror.lock:
            return sum(len(q) for q in self.queue.values())

    def _send(self, cob: int, data: bytes) -> None:
        msg = can.Message(arbitration_id=cob, data=data, is_extended_id=False)
        for _ in range(100):
            try:
                self._bus.send(msg, timeout=0.2)
                return
            except can.CanOperationError as e:
                if getattr(e, "error_code", None) not in (errno.ENOBUFS, errno.EAGAIN):
                    self.errors.append(f"send 0x{cob:03X}: {e}")
                    return
                time.sleep(0.001)
        self.errors.append(f"send 0x{cob:03X}: tx queue full")

    def _run(self) -> None:
        now = time.monotonic()
        t_sync, t_hb = now, now
        while not self._stop.is_set():
            now = time.monotonic()
            if now >= t_hb:
                self._send(0x700 + self.master_id, bytes([self.state]))
                late = now - t_hb >= self.heartbeat_period
                t_hb = (now if late else t_hb) + self.heartbeat_period
            if self.sync_period > 0 and now >= t_sync:
                frames = []
                with self.mirror.lock:
                    for key, q in self.queue.items():
                        if q:
                            self.mirror.values[key] = q.popleft()
                    for pdo in self.sync_rpdos:
                        frames.append((pdo.can_id, pdo.pack(self.mirror.values)))
                for cob, data in frames:
                    self._send(cob, data)
                self._send(COB_SYNC, b"")
                self.cycles += 1
                # The next SYNC a period after this one was due; after a late one no
                # sooner than 3/4 of a period (no bursts: a drive measures its cycle from
                # the SYNC intervals).
                sent = time.monotonic()  # later than `now` if the thread waited (GIL, sockets)
                if sent - t_sync > self.sync_period / 4:
                    self.slips += 1
                t_sync = max(t_sync + self.sync_period, sent + 0.75 * self.sync_period)
            nxt = min(t_hb, t_sync) if self.sync_period > 0 else t_hb
            self._stop.wait(max(0.0, nxt - time.monotonic()))

    def start(self) -> "MasterCycle":
        self._thread.start()
        return self

    def wait_cycles(self, n: int, timeout: float = 3.0) -> None:
        target = self.cycles + n
        deadline = time.monotonic() + timeout
        while self.cycles < target:
            assert time.monotonic() < deadline, f"the SYNC producer made {self.cycles} of {target} cycles"
            time.sleep(0.002)

    def close(self) -> None:
        self._stop.set()
        self._thread.join(2.0)
        self._bus.shutdown()


class Mirror:
    """The master's copy of the node's PDO-mapped objects (what lely's driver writes and
    its PDOs carry)."""

    def __init__(self):
        self.lock = threading.Lock()
        self.values: Dict[Tuple[int, int], int] = {}


@dataclass
class Frame:
    t: float  # kernel receive timestamp
    cob: int
    values: Dict[Tuple[int, int], int]


class Ros2Master:
    """The master side of the test: the boot plan played by SDO, then canopen_402_driver's
    view of the drive through the PDOs the plan configured."""

    def __init__(self, master, plan: BootPlan, eds: Eds, cycle: MasterCycle, mirror: Mirror):
        self.m = master
        self.plan = plan
        self.eds = eds
        self.cycle = cycle
        self.mirror = mirror
        self.node_id = plan.node_id
        self.tpdos = {p.can_id: p for (k, _), p in plan.pdos.items() if k == "tpdo" and p.valid}
        self.rpdos = [p for (k, _), p in sorted(plan.pdos.items()) if k == "rpdo" and p.valid]
        self.events: List[Tuple[str, Frame]] = []  # bus order: ("sync"|"rpdo"|"tpdo", frame)
        self.heartbeats: List[Tuple[float, int]] = []
        self.emcys = []
        self.status_pdo = plan.pdo_with("tpdo", 0x6041)
        self.motion_pdo = plan.pdo_with("tpdo", 0x6064)
        self.cw_pdo = plan.pdo_with("rpdo", 0x6040)
        self.target_pdo = plan.pdo_with("rpdo", 0x607A)
        self.rpdo_cobs = {p.can_id: p for p in self.rpdos}

    # ------------------------------------------------------------ frames
    def _dispatch(self, msg: can.Message) -> None:
        if msg.is_extended_id or msg.is_remote_frame:
            return
        cob, data = msg.arbitration_id, bytes(msg.data)
        if cob in self.tpdos:
            pdo = self.tpdos[cob]
            assert len(data) == struct.calcsize(pdo.fmt), \
                f"TPDO 0x{cob:03X} has {len(data)} bytes, bus.yml's mapping {len(pdo.mapping)} objects / " \
                f"{struct.calcsize(pdo.fmt)} bytes: {data.hex()}"
            self.events.append(("tpdo", Frame(msg.timestamp, cob, pdo.unpack(data))))
        elif cob == COB_SYNC:
            self.events.append(("sync", Frame(msg.timestamp, cob, {})))
        elif cob in self.rpdo_cobs and len(data) == struct.calcsize(self.rpdo_cobs[cob].fmt):
            self.events.append(("rpdo", Frame(msg.timestamp, cob, self.rpdo_cobs[cob].unpack(data))))
        elif cob == 0x700 + self.plan.master_id:
            self.events.append(("mhb", Frame(msg.timestamp, cob, {})))
        elif (hb := decode_heartbeat(msg)) is not None and hb[0] == self.node_id:
            self.heartbeats.append((msg.timestamp, hb[1]))
        elif (e := decode_emcy(msg)) is not None and e.node_id == self.node_id:
            self.emcys.append(e)

    def pump(self, timeout: float, until: Optional[Callable[[], bool]] = None) -> bool:
        deadline = time.monotonic() + timeout
        while True:
            while (msg := self.m.wait_for(lambda _: True, 0)) is not None:
                self._dispatch(msg)
            if until is not None and until():
                return True
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return until is None
            msg = self.m.bus.recv(timeout=min(remaining, 0.02))
            if msg is not None:
                self._dispatch(msg)

    def mark(self) -> int:
        self.pump(0)
        return len(self.events)

    def tpdo_frames(self, pdo: Pdo, start: int = 0) -> List[Frame]:
        return [f for k, f in self.events[start:] if k == "tpdo" and f.cob == pdo.can_id]

    def status_frames(self, start: int = 0) -> List[Frame]:
        return self.tpdo_frames(self.status_pdo, start)

    def sw(self) -> int:
        frames = self.status_frames()
        assert frames, f"no statusword TPDO 0x{self.status_pdo.can_id:03X} seen"
        return frames[-1].values[(0x6041, 0)]

    def position(self) -> int:
        frames = self.tpdo_frames(self.motion_pdo)
        assert frames, f"no position TPDO 0x{self.motion_pdo.can_id:03X} seen"
        return frames[-1].values[(0x6064, 0)]

    def wait_status(self, pred: Callable[[Frame], bool], what: str, timeout: float, start: int) -> Frame:
        found: List[Frame] = []

        def check():
            found[:] = [f for f in self.status_frames(start) if pred(f)][:1]
            return bool(found)

        if not self.pump(timeout, check):
            seen = [(round(f.t, 3), sw_text(f.values[(0x6041, 0)]), f.values.get((0x6061, 0)))
                    for f in self.status_frames(start)][-12:]
            pytest.fail(f"no statusword {what} within {timeout} s on TPDO 0x{self.status_pdo.can_id:03X}; "
                        f"seen: {seen}; EMCY: {[(hex(e.error_code), e.manufacturer.hex()) for e in self.emcys]}",
                        pytrace=False)
        return found[0]

    def recent(self, n: int = 24) -> str:
        return "\n".join(f"  {f.t:.3f} {k} 0x{f.cob:03X} " + " ".join(f"{i:04X}={v}" for (i, _), v in f.values.items())
                         for k, f in self.events[-n:])

    def assert_healthy(self, since_t: float, what: str) -> None:
        """Still operational, no EMCY; if not, say whether the test's own heartbeat stalled."""
        self.pump(0)
        states = [s for t, s in self.heartbeats if t >= since_t]
        beats = [f.t for k, f in self.events if k == "mhb" and f.t >= since_t - 1]
        gap = max((b - a for a, b in zip(beats, beats[1:])), default=0.0)
        why = f"(the master's own heartbeat: largest gap {gap * 1000:.0f} ms, the node's consumer time " \
              f"{self.plan.node_consumer_ms} ms)"
        assert all(s == STATE_OPERATIONAL for s in states), f"{what}: node heartbeat states {states[-6:]} {why}"
        assert not self.emcys, f"{what}: EMCY {[(hex(e.error_code), e.manufacturer.hex()) for e in self.emcys]} {why}"
        assert not self.cycle.errors, self.cycle.errors
        syncs = [f.t for k, f in self.events if k == "sync"]
        short = min((b - a for a, b in zip(syncs, syncs[1:])), default=self.cycle.sync_period)
        assert short >= self.cycle.sync_period / 2, \
            f"{what}: the test's SYNC producer sent two SYNCs {short * 1000:.1f} ms apart (period " \
            f"{self.cycle.sync_period * 1000:.0f} ms): not a regular SYNC"

    # ------------------------------------------------------------ the master's writes
    def set(self, index: int, value: int, sub: int = 0) -> None:
        """Write an object through the PDOs: an event-driven RPDO goes at once, a
        synchronous one with the next SYNC."""
        with self.mirror.lock:
            self.mirror.values[(index, sub)] = value
            now = [p for p in self.rpdos if p.carries(index, sub) and not p.synchronous]
            frames = [(p.can_id, p.pack(self.mirror.values)) for p in now]
        for cob, data in frames:
            self.m.send(cob, data)

    def command(self, cw: int, state: State, mode: Optional[int] = None) -> Frame:
        mark = self.mark()
        if mode is not None:
            with self.mirror.lock:
                self.mirror.values[(0x6060, 0)] = mode
        self.set(0x6040, cw)
        return self.wait_status(lambda f: state(f.values[(0x6041, 0)]), f"in state '{state.name}'", STATE_TIMEOUT, mark)

    # ------------------------------------------------------------ boot (CiA 302-2, lely)
    def boot(self) -> None:
        for index, sub, want, what in self.plan.identity:
            got = self.m.read_u32(self.node_id, index, sub)
            assert got == want, f"boot: 0x{index:04X}:{sub} {what} reads 0x{got:08X}, the EDS says 0x{want:08X}"
        for k, w in enumerate(self.plan.writes, 1):
            data = encode(self.eds, w.index, w.sub, w.value)
            try:
                self.m.sdo_download(self.node_id, w.index, w.sub, data)
            except SdoAbort as e:
                pytest.fail(f"boot write {k}/{len(self.plan.writes)} {w!r} ({data.hex()}): the node aborts with "
                            f"0x{e.code:08X} {ABORT_TEXT.get(e.code, '')}; writes before it: "
                            f"{self.plan.writes[:k - 1]}", pytrace=False)
        # The master's copy of the RPDO-mapped objects starts from what it configured.
        with self.mirror.lock:
            for pdo in self.rpdos:
                for i, s, _ in pdo.mapping:
                    v = self.plan.sdo_value(i, s)
                    self.mirror.values[(i, s)] = self.eds.default(i, s, self.node_id) if v is None else v


def move_time(distance: float, v: float, a: float, d: float) -> float:
    """Duration of a rest-to-rest move on a linear (trapezoid) ramp, 6086h = 0."""
    distance = abs(distance)
    ramps = v * v / (2 * a) + v * v / (2 * d)
    if ramps > distance:  # a triangle: the profile velocity is never reached
        peak = math.sqrt(2 * distance * a * d / (a + d))
        return peak / a + peak / d
    return v / a + (distance - ramps) / v + v / d


def raised_cosine(p0: int, p1: int, duration: float, period: float) -> List[int]:
    n = max(2, round(duration / period))
    return [round(p0 + (p1 - p0) * (1 - math.cos(math.pi * k / n)) / 2) for k in range(1, n + 1)]


def test_ros2_canopen_boot_then_csp_and_pp(example, master, start_node, tmp_path):
    cfg, device, eds, plan, _, _ = example
    assert not plan.problems, plan.problems
    mirror = Mirror()
    period = plan.sync_period_us / 1e6
    cycle = MasterCycle(plan.master_id, period, cfg["master"].get("heartbeat_producer", 0) / 1000 or 1.0, mirror)
    cycle.start()  # the master runs before it boots its slaves: heartbeat and SYNC from the start
    try:
        node = start_node(plan.node_id, ["--config", NODE_TOML])
        r = Ros2Master(master, plan, eds, cycle, mirror)

        # ---- boot: identity, the concise DCF, heartbeat consumption, NMT start
        r.boot()
        t_config = time.time()
        cycle.sync_rpdos = [p for p in r.rpdos if p.synchronous]
        r.pump(0.0)
        n_hb = len(r.heartbeats)
        assert r.pump(plan.master_consumer_ms / 1000 + 0.5, lambda: len(r.heartbeats) > n_hb), \
            f"no heartbeat from node {plan.node_id} within the master's consumer time {plan.master_consumer_ms} ms"
        mark = r.mark()
        cycle.state = STATE_OPERATIONAL
        master.nmt_start(plan.node_id)
        assert r.pump(3.0, lambda: any(s == STATE_OPERATIONAL for _, s in r.heartbeats[n_hb:])), \
            f"node {plan.node_id} does not report operational: heartbeats {r.heartbeats[-5:]}"
        r.pump(0.3)
        t_start = r.heartbeats[-1][0]
        assert r.status_frames(mark), f"no statusword TPDO 0x{r.status_pdo.can_id:03X} after NMT start"
        assert r.tpdo_frames(r.motion_pdo, mark), f"no position TPDO 0x{r.motion_pdo.can_id:03X} on SYNC"
        mode = plan.sdo_value(0x6060)
        assert mode == MODE_CSP, f"bus.yml sets 6060h = {mode}; this test plays CSP then PP"
        assert r.status_frames()[-1].values[(0x6061, 0)] == MODE_CSP, r.status_frames()[-1]

        # ---- the PDS state machine over RPDO/TPDO (canopen_402_driver's init)
        p0 = r.position()
        with mirror.lock:
            mirror.values[(0x607A, 0)] = p0  # CSP: the command value is where the axis is
            mirror.values[(0x60FF, 0)] = 0
        cycle.wait_cycles(2)
        seen = [r.command(CW_SHUTDOWN, READY_TO_SWITCH_ON, MODE_CSP), r.command(CW_SWITCH_ON, SWITCHED_ON),
                r.command(CW_ENABLE_OPERATION, OPERATION_ENABLED)]
        print("enable:", [sw_text(f.values[(0x6041, 0)]) for f in seen])

        # ---- CSP: one set-point per SYNC, RPDO (synchronous) then SYNC
        distance = 3000
        points = raised_cosine(p0, p0 + distance, 1.5, period) + [p0 + distance] * round(0.2 / period)
        mark = r.mark()
        cycle.stream(0x607A, points)
        r.pump(len(points) * period * 3 + 2.0, lambda: cycle.pending() == 0)
        cycle.wait_cycles(5)
        r.pump(0.2)
        r.assert_healthy(t_start, "CSP")
        status = r.status_frames(mark)
        assert all(OPERATION_ENABLED(f.values[(0x6041, 0)]) for f in status), \
            [sw_text(f.values[(0x6041, 0)]) for f in status]
        assert not any(f.values[(0x6041, 0)] & SW_FOLLOWING_ERROR for f in status), "following error during CSP"
        assert r.sw() & SW_DRIVE_FOLLOWS, f"CSP: bit 12 (drive follows) clear: {sw_text(r.sw())}"
        end = master.read_i32(plan.node_id, 0x6064)
        if end != p0 + distance:
            moved = [f.values[(0x6064, 0)] for f in r.tpdo_frames(r.motion_pdo, mark)]
            most = max((abs(b - a) for a, b in zip(moved, moved[1:])), default=0)
            asked = max(abs(b - a) for a, b in zip([p0] + points, points))
            pytest.fail(f"CSP: 6064h = {end} after the stream to {p0 + distance}: the axis moved at most {most} "
                        f"steps between two position TPDOs (one a SYNC) where the set-points asked up to {asked} "
                        f"a SYNC, with no following error signalled; last frames:\n{r.recent()}", pytrace=False)
        # A TPDO sampled at SYNC k+1 shows the set-point of SYNC k (reached one cycle
        # later, linear interpolation): exactly with a regular SYNC. With SYNC jitter the
        # axis may not be there yet (a SYNC that comes early cuts the segment short, the
        # rest is folded into the next): never beyond the command, and, over two early
        # SYNCs in a row, no further behind than the set-point two SYNCs before.
        setpoints: List[Optional[int]] = [None] * 4  # SYNC k-2, k-1, k, k+1 (this one)
        pending_rpdo, worst, off, moving = None, 0, [], set()
        for kind, f in r.events[mark:]:
            if kind == "rpdo" and f.cob == r.target_pdo.can_id:
                pending_rpdo = f.values[(0x607A, 0)]
            elif kind == "sync":
                setpoints = setpoints[1:] + [pending_rpdo]
                pending_rpdo = None
            elif kind == "tpdo" and f.cob == r.motion_pdo.can_id and None not in setpoints[:3]:
                pos, (behind, _, reached, _) = f.values[(0x6064, 0)], setpoints
                worst = max(worst, abs(pos - reached))
                if not min(behind, reached) - 2 <= pos <= max(behind, reached) + 2:
                    off.append((round(f.t, 3), pos, behind, reached))
                if p0 < pos < p0 + distance:
                    moving.add(pos)
        max_step = max(abs(b - a) for a, b in zip([p0] + points, points))
        print(f"CSP: {len(points)} set-points, {cycle.slips} late cycles; |actual - set-point of the SYNC before| "
              f"worst {worst} steps (a cycle's step is up to {max_step}); {len(moving)} positions on the way")
        assert len(moving) >= len(points) // 3, f"CSP: only {len(moving)} intermediate positions: the axis jumped"
        if off:
            moved = [f.values[(0x6064, 0)] for f in r.tpdo_frames(r.motion_pdo, mark)]
            most = max((abs(b - a) for a, b in zip(moved, moved[1:])), default=0)
            pytest.fail(f"CSP: {len(off)} position TPDOs outside [set-point k-2, set-point k] at SYNC k+1 (the axis "
                        f"moved at most {most} steps a SYNC, the set-points asked up to {max_step}); (t, actual, "
                        f"set-point k-2, set-point k): {off[:8]}", pytrace=False)

        # ---- PP: mode 1 over RPDO1, set-point handshake, target reached
        mark = r.mark()
        r.set(0x6060, MODE_PP)
        r.set(0x6040, CW_ENABLE_OPERATION)
        r.wait_status(lambda f: f.values[(0x6061, 0)] == MODE_PP, "with 6061h = 1 (pp)", 1.0, mark)
        target = end + 2000
        r.set(0x607A, target)  # synchronous RPDO: taken over at the next SYNC
        cycle.wait_cycles(2)
        mark = r.mark()
        r.set(0x6040, CW_ENABLE_OPERATION | CW_NEW_SET_POINT)
        ack = r.wait_status(lambda f: f.values[(0x6041, 0)] & SW_SET_POINT_ACK, "with set-point acknowledge",
                            STATE_TIMEOUT, mark)
        r.set(0x6040, CW_ENABLE_OPERATION)
        r.wait_status(lambda f: not f.values[(0x6041, 0)] & SW_SET_POINT_ACK, "with set-point acknowledge cleared",
                      STATE_TIMEOUT, mark)
        v, a, d = (plan.sdo_value(i) for i in (0x6081, 0x6083, 0x6084))
        t_move = move_time(target - end, v, a, d)
        done = r.wait_status(lambda f: f.t > ack.t and f.values[(0x6041, 0)] & SW_TARGET_REACHED,
                             "with target reached", t_move * 3 + 2.0, mark)
        assert master.read_i32(plan.node_id, 0x6064) == target
        r.pump(4 * period, lambda: any(f.values[(0x6064, 0)] == target for f in r.tpdo_frames(r.motion_pdo, mark)))
        arrived = [f for f in r.tpdo_frames(r.motion_pdo, mark) if f.values[(0x6064, 0)] == target]
        assert arrived, f"PP: no position TPDO 0x{r.motion_pdo.can_id:03X} shows {target}; last frames:\n{r.recent()}"
        took = arrived[0].t - ack.t
        print(f"PP: {end} -> {target} in {took * 1000:.0f} ms by the position TPDOs (profile {v}/{a}/{d}: "
              f"{t_move * 1000:.0f} ms); target reached at {(done.t - ack.t) * 1000:.0f} ms")
        assert t_move - 0.06 <= took <= t_move + 0.06 + 3 * period + 0.1, \
            f"PP move took {took * 1000:.0f} ms, the profile bus.yml sets gives {t_move * 1000:.0f} ms"

        # ---- disable, and what the master watched all along
        r.command(CW_SHUTDOWN, READY_TO_SWITCH_ON)
        r.pump(0.1)
        r.assert_healthy(t_start, "end")
        beats = [t for t, _ in r.heartbeats if t >= t_config]
        gaps = [b - a for a, b in zip(beats, beats[1:])]
        assert gaps and max(gaps) * 1000 < plan.master_consumer_ms, \
            f"node heartbeat gap {max(gaps) * 1000:.0f} ms > the master's consumer time {plan.master_consumer_ms} ms"
        assert not cycle.errors, cycle.errors
        assert node.alive
    finally:
        cycle.close()
        if "r" in locals():  # every frame of the run, for a look after a failure
            rows = [(k, f.t, f"0x{f.cob:03X}", {f"{i:04X}:{s}": v for (i, s), v in f.values.items()})
                    for k, f in r.events]
            (tmp_path / "frames.json").write_text(json.dumps(rows))
            print(f"frames of the run: {tmp_path / 'frames.json'}")


def test_node_serves_the_committed_eds(example, master, start_node):
    _, _, _, plan, _, eds_path = example
    start_node(plan.node_id, ["--config", NODE_TOML])
    served = master.sdo_block_upload(plan.node_id, 0x1021, 0)
    assert_same_eds(served.decode(errors="replace"), eds_path, "the EDS the node serves on 0x1021")
