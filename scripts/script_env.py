"""A script's own Python packages, in a virtual environment beside scripts/.

    import script_env
    script_env.ensure(".venv-opencv", ["opencv-python-headless", "numpy"], ["cv2", "numpy"])

If the modules import, nothing happens. Otherwise the environment is made
(first use only), the packages installed into it, and the calling script
re-run inside it with the same arguments.
"""
import fcntl
import importlib
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))


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
    # Tests run scripts in parallel: one makes the environment, the others
    # wait for it; a half-made one (an interrupted install) is made again.
    with open(directory + ".lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        # The marker names what was installed: a script that asks for more
        # packages gets an environment made again.
        done, wanted = os.path.join(directory, ".installed"), "\n".join(packages)
        if not os.path.exists(done) or open(done).read() != wanted:
            subprocess.check_call([sys.executable, "-m", "venv", "--clear", directory])
            subprocess.check_call([python, "-m", "pip", "install", "--quiet", *packages])
            with open(done, "w") as marker:
                marker.write(wanted)
    os.execv(python, [python] + sys.argv)
