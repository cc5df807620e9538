"""What `pip install .` puts into a user's environment: urdf2links with its compare and robots
subpackages, no top-level `compare`, and shipped scenes that load from any folder."""

from __future__ import annotations

import functools
import os
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def _declared() -> dict[str, str]:
    """Installed package name -> source folder, from pyproject.toml."""
    tool = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    mapping = tool.get("package-dir", {})
    out = {}
    for name in tool["packages"]:
        parent = next((k for k in sorted(mapping, key=len, reverse=True) if name == k or name.startswith(k + ".")), None)
        folder = mapping[parent] + name[len(parent):].replace(".", "/") if parent else name.replace(".", "/")
        out[name] = folder
    return out


def test_every_package_folder_is_declared():
    """A subpackage missing from pyproject's explicit list installs nothing and breaks imports after
    a plain `pip install .` (an editable install hides it)."""
    declared = set(_declared().values())
    found = {str(p.parent.relative_to(ROOT)) for top in ("urdf2links", "compare", "robots")
             for p in (ROOT / top).rglob("__init__.py")}
    assert found == declared, f"undeclared: {sorted(found - declared)}; declared but absent: {sorted(declared - found)}"


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """The wheel built from a clean copy of this checkout (no build/ or *.egg-info left by earlier
    builds: setuptools would ship files listed there even when pyproject no longer declares them),
    unpacked into a folder of its own (dependencies from the running environment)."""
    src = tmp_path_factory.mktemp("src") / "urdf2links"
    generic = shutil.ignore_patterns(".git", "build", "*.egg-info", "__pycache__", ".pytest_cache")

    def ignore(folder, names):      # the generated reports/ and out/ at the top only (compare/reports is code)
        top = {"reports", "out"} & set(names) if Path(folder) == ROOT else set()
        return set(generic(folder, names)) | top

    shutil.copytree(ROOT, src, ignore=ignore)
    out = tmp_path_factory.mktemp("wheel")
    build = subprocess.run([sys.executable, "-m", "pip", "wheel", str(src), "--no-deps",
                            "-q", "-w", str(out)], capture_output=True, text=True)
    if build.returncode != 0:
        pytest.fail(f"building the wheel failed: {build.stderr[-2000:]}")
    wheel = next(out.glob("urdf2links-*.whl"))
    target = tmp_path_factory.mktemp("site")
    with zipfile.ZipFile(wheel) as z:
        names = z.namelist()
        z.extractall(target)
    BUILT.update(wheel=wheel, src=src)
    return target, names


#: the wheel and the clean source copy the ``installed`` fixture built (for the install tests)
BUILT: dict = {}


def test_wheel_installs_compare_and_robots_inside_the_package(installed):
    _, names = installed
    tops = {n.split("/")[0] for n in names}
    assert tops <= {"urdf2links", *(t for t in tops if t.endswith(".dist-info"))}, tops
    for needed in ("urdf2links/compare/agreement/trajectory.py", "urdf2links/integration/loops/driver.py", "urdf2links/dynamics/oracles/literal.py",
                   "urdf2links/robots/ur5_falling.toml", "urdf2links/robots/ur5_like.urdf",
                   "urdf2links/robots/hard/chain32.urdf", "urdf2links/robots/README.md"):
        assert needed in names, needed


def test_installed_package_works_from_another_folder(installed, tmp_path):
    target, _ = installed
    # an editable install of this checkout (the test extra's usual set-up) adds a meta-path finder
    # that would serve any urdf2links module the wheel lacks: drop it, so only the wheel answers
    code = ("import sys, importlib.util\n"
            "sys.meta_path[:] = [f for f in sys.meta_path if '__editable__' not in getattr(f, '__module__', '')\n"
            "                    and '__editable__' not in getattr(f, '__name__', '')]\n"
            "assert importlib.util.find_spec('compare') is None, 'a top-level compare is importable'\n"
            "import urdf2links\n"
            "assert 'mujoco' not in sys.modules\n"
            "import urdf2links.compare\n"
            "from urdf2links.locations import shipped_robots_dir\n"
            "from urdf2links.scenes.scene_read import load_scene\n"
            f"assert shipped_robots_dir().is_relative_to({str(target)!r}), shipped_robots_dir()\n"
            "s = load_scene(shipped_robots_dir() / 'ur5_falling.toml')\n"
            "print(s.model().n)\n")
    env = {"PYTHONPATH": str(target), "PATH": "/usr/bin:/bin"}
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, env=env)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "6"


# --------------------------------------------------------------------------- install, run, reinstall


def _running_site_dirs() -> list[str]:
    """The running environment's package folders, in import order: its site-packages (a venv's, a conda
    env's or the system's dist-packages), the user's site if it is on the path, and folders that its
    ``.pth`` files added (cmeel's prefix). Never the base interpreter's, unless that is what runs."""
    import site

    dirs = [*site.getsitepackages(), *([site.getusersitepackages()] if site.ENABLE_USER_SITE else [])]
    dirs += [p for p in sys.path if p.endswith(("site-packages", "dist-packages"))]
    return [d for d in dict.fromkeys(dirs) if Path(d).is_dir()]


def _venv(folder: Path) -> tuple[Path, Path]:
    """A fresh virtual environment that installs urdf2links into its own site-packages and sees the
    RUNNING environment's packages (the dependencies) behind them: a ``.pth`` file names the running
    environment's package folders. ``--system-site-packages`` would show the base interpreter's
    packages instead, which lack numba when the suite itself runs in a venv (issue 31). The folders are
    added as plain paths: their own ``.pth`` files (an editable install of this checkout among them) are
    not run, so the venv's own urdf2links is the one imported. ``(its bin folder, its site-packages)``."""
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(folder)], check=True)
    bin_ = folder / "bin"
    site = Path(subprocess.run([str(bin_ / "python"), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                               capture_output=True, text=True, check=True).stdout.strip())
    (site / "_running_env.pth").write_text("".join(f"{d}\n" for d in _running_site_dirs()))
    return bin_, site


def _user_env(home: Path, bin_: Path) -> dict:
    """A user's environment: their own home and cache folder, no numba cache setting, this venv first."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("NUMBA_CACHE_DIR", "URDF2LINKS_CACHE_DIR", "PYTHONPATH", "XDG_CACHE_HOME")}
    env.update(HOME=str(home), XDG_CACHE_HOME=str(home / ".cache"), PATH=f"{bin_}:{env.get('PATH', '')}")
    return env


def _recorded(site: Path) -> set[str]:
    record = next(site.glob("urdf2links-*.dist-info")) / "RECORD"
    return {line.split(",")[0] for line in record.read_text().splitlines() if line}


def _package_files(site: Path) -> set[str]:
    return {str(p.relative_to(site)) for p in (site / "urdf2links").rglob("*") if p.is_file()}


def test_install_run_then_reinstall_editable(installed, tmp_path):
    """Issue 22: ``pip install .``, a run (numba compiles and caches), then ``pip install -e .``: the
    command must still start. numba used to cache into site-packages/urdf2links/**/__pycache__; pip's
    uninstall left those folders, and the leftover urdf2links/ became a namespace package that hid the
    editable install. Now the run writes nothing under site-packages, the cache is in the user's
    cache folder, and the reinstall leaves no trace of the old install."""
    bin_, site = _venv(tmp_path / "venv")
    subprocess.run([str(bin_ / "python"), "-m", "pip", "install", "-q", "--no-deps", str(BUILT["wheel"])], check=True)
    env = _user_env(tmp_path / "home", bin_)
    work = tmp_path / "work"
    work.mkdir()
    before = _package_files(site)
    assert before <= _recorded(site)
    run = subprocess.run([str(bin_ / "urdf2links"), "sweep", "pendulum", "--count", "2", "--t-end", "0.01"], cwd=work,
                         env=env, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert "compiling the solver for this machine, first run only" in run.stderr   # a fresh cache: said apart
    written = _package_files(site) - before
    assert not written, f"files written into the installed package: {sorted(written)[:5]}"
    assert list((tmp_path / "home" / ".cache" / "urdf2links" / "numba").rglob("*.nbi")), "no numba cache"
    subprocess.run([str(bin_ / "python"), "-m", "pip", "install", "-q", "--no-deps", "-e", str(BUILT["src"])],
                   check=True, capture_output=True)
    assert not (site / "urdf2links").exists(), "the uninstall left urdf2links/ behind (a namespace package)"
    again = subprocess.run([str(bin_ / "urdf2links"), "inspect", "ur5_like"], cwd=work, env=env, capture_output=True,
                           text=True)
    assert again.returncode == 0 and "6 coordinates" in again.stdout, again.stderr
    where = subprocess.run([str(bin_ / "python"), "-c", "import urdf2links; print(urdf2links.__file__)"], cwd=work,
                           env=env, capture_output=True, text=True)
    assert Path(where.stdout.strip()).is_relative_to(BUILT["src"]), where.stdout + where.stderr


def _read_only(site: Path, argv: list[str]) -> list[str]:
    """``argv`` run with the installed package read-only: a read-only bind mount in a mount namespace
    of its own when running as root (root writes through file modes), file modes otherwise."""
    pkg = site / "urdf2links"
    if os.geteuid() == 0:
        if not shutil.which("unshare"):
            pytest.fail("running as root, a read-only install needs `unshare` (util-linux) for a read-only mount")
        return ["unshare", "-m", "sh", "-c", f'mount --bind -o ro "{pkg}" "{pkg}" && exec "$@"', "sh", *argv]
    for p in [pkg, *pkg.rglob("*")]:
        p.chmod(p.stat().st_mode & ~0o222)
    return argv


def test_a_read_only_install_runs(installed, tmp_path):
    bin_, site = _venv(tmp_path / "venv")
    subprocess.run([str(bin_ / "python"), "-m", "pip", "install", "-q", "--no-deps", str(BUILT["wheel"])], check=True)
    env = _user_env(tmp_path / "home", bin_)
    probe = subprocess.run(_read_only(site, [str(bin_ / "python"), "-c",
                                             f"open({str(site / 'urdf2links' / 'probe')!r}, 'w')"]),
                           env=env, capture_output=True, text=True)
    assert probe.returncode != 0, "the install is not read-only: this test would prove nothing"
    run = subprocess.run(_read_only(site, [str(bin_ / "urdf2links"), "simulate", "pendulum", "--t-end", "0.01",
                                           "--method", "RK4", "--dt", "0.001"]),
                         cwd=tmp_path, env=env, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "out" / "pendulum_default.npz").is_file()


# --------------------------------------------------------------------------- declared dependencies

#: import name -> distribution, where importlib.metadata cannot tell (cmeel installs Pinocchio outside
#: the distribution's top-level listing)
IMPORT_ALIASES = {"pinocchio": "pin"}
#: declared but never imported: trimesh loads pycollada itself to read .dae meshes; the animation inlines
#: the viewer bundle the meshcat package ships (urdf2links.view.animation reads the file: importing meshcat
#: would start its zmq server)
USED_WITHOUT_IMPORT = {"pycollada", "meshcat"}


def _requirement_names(requirements) -> set[str]:
    import re

    return {re.split(r"[\s<>=!~;\[(]", r, maxsplit=1)[0].lower().replace("_", "-") for r in requirements}


def _declared_dependencies() -> tuple[set[str], dict[str, set[str]]]:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    extras = {k: _requirement_names(v) for k, v in project.get("optional-dependencies", {}).items()}
    return _requirement_names(project["dependencies"]), extras


def _third_party_imports(folders) -> dict[str, set[str]]:
    """Top-level third-party module names imported anywhere under ``folders`` -> the files importing them
    (the project's own packages and the test and benchmark helpers excluded)."""
    import ast

    local = {"urdf2links", "compare"} | {p.stem for d in ("tests", "benchmarks") for p in (ROOT / d).glob("*.py")}
    found: dict[str, set[str]] = {}
    for folder in folders:
        for path in (ROOT / folder).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.Import):
                    names = [a.name for a in node.names]
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    names = [node.module]
                else:
                    continue
                for name in names:
                    top = name.split(".")[0]
                    if top not in sys.stdlib_module_names and top not in local:
                        found.setdefault(top, set()).add(str(path.relative_to(ROOT)))
    return found


@functools.cache
def _packages_distributions() -> dict:
    import importlib.metadata

    return importlib.metadata.packages_distributions()   # scans every installed distribution: once


def _distributions(module: str) -> set[str]:
    if module in IMPORT_ALIASES:
        return {IMPORT_ALIASES[module]}
    return {n.lower().replace("_", "-") for n in _packages_distributions().get(module, [])}


def test_every_import_is_a_declared_dependency():
    """Every third-party module urdf2links/ and compare/ import is a declared dependency, or (xacro, Dask) an
    extra whose absence gives a clear message (tests/test_xacro.py checks that message); what tests/ and
    benchmarks/ import besides is in the test extra. lxml, imported by the URDF reader, once arrived only
    through yourdfpy. Every declared dependency is imported somewhere (or listed in USED_WITHOUT_IMPORT)."""
    runtime, extras = _declared_dependencies()
    # imported inside a function: xacro's ImportError -> URDFError naming the extra; Dask's -> ImportError
    # naming the extra (urdf2links.integration.distributed; the corpus runner takes a client the caller made)
    optional = {"xacro": extras["xacro"], "distributed": extras["distributed"],
                "logs": extras["logs"],     # rosbags: LogFormatError naming the extra (tests/test_robot_logs.py)
                "identify": extras["identify"]}     # cvxpy: ImportError naming the extra (identification.consistency)
    problems = []
    used = set()
    for module, files in sorted(_third_party_imports(["urdf2links", "compare"]).items()):
        dists = _distributions(module)
        used |= dists
        if module == "pytest" and files == {"urdf2links/pytest_plugin.py"}:
            continue        # the pytest plugin (an entry point) is only ever loaded by a running pytest
        if not dists & runtime and not any(dists & e for e in optional.values()):
            problems.append(f"{module} (distribution {sorted(dists) or 'unknown'}) imported by {sorted(files)} "
                            "is not in [project] dependencies")
    for module, files in sorted(_third_party_imports(["tests", "benchmarks"]).items()):
        dists = _distributions(module)
        used |= dists
        if not dists & (runtime | extras["test"]):
            problems.append(f"{module} (distribution {sorted(dists) or 'unknown'}) imported by {sorted(files)} "
                            "is neither a dependency nor in the test extra")
    unused = runtime - used - USED_WITHOUT_IMPORT
    assert not problems, "\n".join(problems)
    assert not unused, f"declared dependencies nothing imports: {sorted(unused)}"


def test_the_test_extra_is_installed():
    """The suite runs with the test extra (README, .ci/run): a missing or broken test dependency fails here
    by name, instead of letting the tests that need it skip."""
    import importlib.metadata

    runtime, extras = _declared_dependencies()
    missing = []
    for name in sorted(runtime | extras["test"]):
        try:
            importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            missing.append(name)
    assert not missing, f"not installed: {missing}; pip install -e '.[test]'"
