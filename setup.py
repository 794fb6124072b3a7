"""`pip install .`: the package hbirl (python/hbirl) with its extension module built by
the project's own CMake (only the libraries it links: -DHBIRL_PYTHON_ONLY=ON) for the
Python that runs pip. README.md "Python" says how to run it offline."""
import os
import re
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = os.path.dirname(os.path.abspath(__file__))


def version():
    with open(os.path.join(ROOT, "CMakeLists.txt"), encoding="utf-8") as f:
        return re.search(r"project\(hbirl VERSION ([0-9.]+)", f.read()).group(1)


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build = os.path.abspath(os.path.join(self.build_temp, "cmake"))
        subprocess.check_call(["cmake", "-S", ROOT, "-B", build, "-DCMAKE_BUILD_TYPE=Release", "-DHBIRL_PYTHON_ONLY=ON",
                               "-DHBIRL_BUILD_TESTS=OFF", "-DHBIRL_BUILD_BENCH=OFF", f"-DPYTHON_EXECUTABLE={sys.executable}"])
        subprocess.check_call(["cmake", "--build", build, "--target", "hbirl_python", "-j", str(os.cpu_count() or 1)])
        built = [f for f in os.listdir(os.path.join(build, "python", "hbirl")) if f.startswith("_hbirl") and f.endswith(".so")]
        if len(built) != 1:
            raise RuntimeError(f"hbirl: expected one _hbirl*.so in {build}/python/hbirl, found {built}")
        target = self.get_ext_fullpath(ext.name)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copyfile(os.path.join(build, "python", "hbirl", built[0]), target)


setup(
    version=version(),
    packages=["hbirl"],
    package_dir={"hbirl": "python/hbirl"},
    package_data={"hbirl": ["*.pyi", "py.typed"]},
    ext_modules=[Extension("hbirl._hbirl", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    zip_safe=False,
)
