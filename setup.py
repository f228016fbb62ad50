"""Builds keymesh._keymesh with the project's CMake build (see pyproject.toml).

Everything setuptools writes goes under build-pip/ (ignored by git), never
under build/. KEYMESH_CMAKE_ARGS adds CMake options; KEYMESH_JOBS sets the
build parallelism.
"""
import os
import pathlib
import shlex
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = pathlib.Path(__file__).resolve().parent
BUILD_BASE = ROOT / "build-pip"


class CMakeExtension(Extension):
    def __init__(self, name):
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        target = pathlib.Path(self.get_ext_fullpath(ext.name)).resolve()
        tree = BUILD_BASE / "cmake"
        configure = ["cmake", "-S", str(ROOT), "-B", str(tree), "-DCMAKE_BUILD_TYPE=Release",
                     "-DKEYMESH_PYTHON=ON", "-DKEYMESH_BUILD_TESTS=OFF", "-DKEYMESH_BUILD_BENCH=OFF",
                     f"-DPython3_EXECUTABLE={sys.executable}"]
        if shutil.which("ninja") and not (tree / "CMakeCache.txt").exists():
            configure += ["-G", "Ninja"]
        configure += shlex.split(os.environ.get("KEYMESH_CMAKE_ARGS", ""))
        subprocess.check_call(configure)
        jobs = os.environ.get("KEYMESH_JOBS", str(os.cpu_count() or 1))
        subprocess.check_call(["cmake", "--build", str(tree), "--target", "keymesh_python", "keymesh", "-j", jobs])
        built = sorted((tree / "python" / "keymesh").glob("_keymesh*.so"))
        if not built:
            raise RuntimeError("CMake did not build keymesh._keymesh (is pybind11-dev installed?)")
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built[0], target)
        # The command itself, for `python -m keymesh` (keymesh/__main__.py).
        exe = target.parent / "bin" / "keymesh"
        exe.parent.mkdir(exist_ok=True)
        shutil.copyfile(tree / "keymesh", exe)
        exe.chmod(0o755)
        # Modules opened on first use are looked for beside the binary holding
        # the caller: GDCM's (DICOM reads) beside the extension and the
        # command, MPI's (runs under mpirun; built when MPI was found) beside
        # the command.
        gdcm = tree / "libkeymesh_gdcm.so"
        if not gdcm.exists():
            raise RuntimeError(f"CMake did not build {gdcm}")
        for folder in (target.parent, exe.parent):
            shutil.copyfile(gdcm, folder / gdcm.name)
        mpi = tree / "libkeymesh_mpi.so"
        if mpi.exists():
            shutil.copyfile(mpi, exe.parent / mpi.name)


BUILD_BASE.mkdir(exist_ok=True)
setup(
    packages=["keymesh"],
    package_dir={"keymesh": "python/keymesh"},
    package_data={"keymesh": ["*.pyi", "py.typed", "bin/keymesh", "*.so", "bin/*.so"]},
    ext_modules=[CMakeExtension("keymesh._keymesh")],
    cmdclass={"build_ext": CMakeBuild},
    options={"build": {"build_base": str(BUILD_BASE)}, "egg_info": {"egg_base": str(BUILD_BASE)}},
    zip_safe=False,
)
