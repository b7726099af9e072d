"""`python -m jaxrock`: the `jaxrock` command line, for an environment whose scripts are not on PATH."""

from .cli.app import main

main()
