#!/usr/bin/env bash
echo "[demo] not yet available: the demo lands with the demo/benchmark issue" >&2
exit 2
