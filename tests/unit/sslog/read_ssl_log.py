#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""An SSL log file reader written from the format's description alone (docs/log-files.md), with
no code shared with apps/sslog: the check that ÜberSim's writer writes what others read.

    read_ssl_log.py FILE

Prints one line per record: `timestamp type size sha1-of-payload` (decimal, decimal, decimal,
hex), then, when the last record is an index, `index OFFSET OFFSET ...` as found by the
format's detection rule (the file's last 7 bytes are INDEXED). Exit code 1 and a message on
stderr for a file that is not an SSL log file of version 1 or ends inside a record.
"""
import gzip
import hashlib
import struct
import sys


def main(path):
    with open(path, "rb") as f:
        data = f.read()
    # By name, as the league's tools decide.
    if path.endswith(".gz"):
        data = gzip.decompress(data)
    if data[:12] != b"SSL_LOG_FILE":
        sys.exit(f"{path}: not an SSL log file")
    (version,) = struct.unpack(">i", data[12:16])
    if version != 1:
        sys.exit(f"{path}: version {version}")
    pos = 16
    while pos < len(data):
        if len(data) - pos < 16:
            sys.exit(f"{path}: truncated record header at {pos}")
        timestamp, kind, size = struct.unpack(">qii", data[pos:pos + 16])
        if size < 0 or len(data) - pos - 16 < size:
            sys.exit(f"{path}: bad or truncated payload at {pos}")
        payload = data[pos + 16:pos + 16 + size]
        print(f"{timestamp} {kind} {size} {hashlib.sha1(payload).hexdigest()}")
        pos += 16 + size
    if data.endswith(b"INDEXED"):
        (length,) = struct.unpack(">q", data[-15:-7])
        start = len(data) - length + 16
        count = (len(data) - 15 - start) // 8
        offsets = struct.unpack(f">{count}q", data[start:start + 8 * count])
        print("index " + " ".join(str(o) for o in offsets))


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: read_ssl_log.py FILE")
    main(sys.argv[1])
