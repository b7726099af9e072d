"""`pytest --nbmake notebooks/` runs every notebook in its quick mode: each reads
`JAXROCK_NOTEBOOK_QUICK` in its parameter cell (the kernel inherits this process's environment).
Opened in Jupyter, without the variable, a notebook runs its full study."""

import os

os.environ.setdefault("JAXROCK_NOTEBOOK_QUICK", "1")
