"""The `translucency` executable the Python tests run (shared by the tests of
Testing/Python; ctest sets TRANSLUCENCY_CLI or TRANSLUCENCY_BINARY_DIR)."""

import os
import sys


def find_cli(test_name):
    """$TRANSLUCENCY_CLI, else $TRANSLUCENCY_BINARY_DIR/bin/translucency; exits
    with a message naming `test_name` when neither is an executable."""
    cli = os.environ.get("TRANSLUCENCY_CLI")
    if not cli:
        binary = os.environ.get("TRANSLUCENCY_BINARY_DIR")
        if binary:
            cli = os.path.join(binary, "bin", "translucency")
    if not cli or not os.access(cli, os.X_OK):
        sys.exit("%s: set TRANSLUCENCY_CLI to the built translucency executable (got %r)"
                 % (test_name, cli))
    return cli
