"""A script's own Python packages, in a virtual environment beside scripts/.

    import script_env
    script_env.ensure(".venv-opencv", ["opencv-python-headless", "numpy"], ["cv2", "numpy"])

If the modules import, nothing happens. Otherwise the environment is made
(first use only), the packages installed into it, and the calling script
re-run inside it with the same arguments.
"""
import importlib
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def ensure(name, packages, modules):
    try:
        for module in modules:
            importlib.import_module(module)
        return
    except ImportError:
        pass
    directory = os.path.join(ROOT, name)
    python = os.path.join(directory, "bin", "python")
    if os.path.abspath(sys.executable) == os.path.abspath(python):
        sys.exit(f"{', '.join(modules)} not importable in {directory}")
    if not os.path.exists(python):
        subprocess.check_call([sys.executable, "-m", "venv", directory])
        subprocess.check_call([python, "-m", "pip", "install", "--quiet", *packages])
    os.execv(python, [python] + sys.argv)
