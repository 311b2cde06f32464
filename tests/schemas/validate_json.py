#!/usr/bin/env python3
"""Validates a JSON file against a JSON Schema with the jsonschema package (Debian: python3-jsonschema).

usage: validate_json.py SCHEMA FILE
exit code: 0 valid, 1 invalid (the first error on stderr), 2 jsonschema missing or unreadable input.
"""
import json
import sys

try:
    import jsonschema
except ImportError:
    sys.exit("validate_json.py: the Python package jsonschema is missing (apt-get install python3-jsonschema)")

if len(sys.argv) != 3:
    sys.exit(__doc__)
with open(sys.argv[1], encoding="utf-8") as f:
    schema = json.load(f)
with open(sys.argv[2], encoding="utf-8") as f:
    document = json.load(f)
validator = jsonschema.Draft7Validator(schema)
validator.check_schema(schema)
errors = sorted(validator.iter_errors(document), key=lambda e: list(e.path))
for error in errors[:5]:
    print(f"{sys.argv[2]}: at /{'/'.join(str(p) for p in error.path)}: {error.message}", file=sys.stderr)
sys.exit(1 if errors else 0)
