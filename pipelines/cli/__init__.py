"""The ``fretwork`` command line; its JSON is :func:`pipelines.output.jsonfile.json_text`."""

from pipelines.output.jsonfile import json_text  # noqa: F401  (the commands import it from here)
