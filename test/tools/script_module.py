"""The tools tests' way into a script of scripts/: its file has no .py suffix, so it is loaded as a
module from its path (its main() is not run), and a test may replace its functions."""
import importlib.machinery
import importlib.util
import os


def load(scripts_dir, filename):
    """scripts_dir/filename as a module named after it (dashes as underscores)."""
    name = filename.replace("-", "_")
    loader = importlib.machinery.SourceFileLoader(name, os.path.join(scripts_dir, filename))
    module = importlib.util.module_from_spec(importlib.util.spec_from_loader(name, loader))
    loader.exec_module(module)
    return module
