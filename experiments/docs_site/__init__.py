"""The documentation site's generated pages: the command-line and scenario-schema reference.

`reference` writes them from the real argparse parsers and pydantic models; `hook` hands them to MkDocs.
"""
