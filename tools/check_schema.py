"""Validate a JSON file against a JSON Schema: check_schema.py SCHEMA FILE (exit 1 on errors)."""
import json
import sys

import jsonschema

schema = json.load(open(sys.argv[1]))
jsonschema.Draft202012Validator.check_schema(schema)
errors = list(jsonschema.Draft202012Validator(schema).iter_errors(json.load(open(sys.argv[2]))))
for e in errors[:10]:
    print(f"{list(e.path)}: {e.message}")
sys.exit(1 if errors else 0)
