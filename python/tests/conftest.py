# The plugin from the tree, without installing the package (pip install ./python registers it instead).
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
pytest_plugins = ["vecat.pytest_plugin"]
