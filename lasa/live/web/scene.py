"""The robot drawn in the browser (``--frames browser``): MuJoCo's WebAssembly build and three.js, served by
the server itself (:class:`NpmFiles`), and the trial's scene, its files renamed by :func:`browser_scene`: no
string from a client ever reaches a path."""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from pathlib import Path

from starlette.responses import Response
from starlette.staticfiles import StaticFiles
from starlette.types import Scope

from lasa.base.errors import ArtifactError
from lasa.base.paths import repo_root

# The npm packages the page loads: URL name -> (folder under .venv, the file that must be there).
NPM_PACKAGES = {"mujoco": ("mujoco-js", "mujoco.wasm"), "three": ("three", "three.module.js")}
# The scene's asset files the page may fetch, by suffix, with their content types.
ASSET_TYPES = {
    ".stl": "model/stl",
    ".obj": "model/obj",
    ".msh": "application/octet-stream",
    ".png": "image/png",
}


def npm_folder(name: str) -> Path:
    """Where ``make setup`` put npm package ``name`` (a key of :data:`NPM_PACKAGES`); else ArtifactError."""
    folder, marker = NPM_PACKAGES[name]
    path = repo_root() / ".venv" / folder
    if not (path / marker).is_file():
        raise ArtifactError(f"{path / marker} is missing (the page draws the robot with it): run make setup")
    return path


class NpmFiles(StaticFiles):
    """A read-only folder of an npm package: ``.wasm`` as ``application/wasm``, ``.js`` as JavaScript,
    cacheable (the folder holds one pinned version)."""

    TYPES = {".wasm": "application/wasm", ".js": "text/javascript", ".mjs": "text/javascript"}

    def file_response(
        self,
        full_path: str | os.PathLike[str],
        stat_result: os.stat_result,
        scope: Scope,
        status_code: int = 200,
    ) -> Response:
        response = super().file_response(full_path, stat_result, scope, status_code)
        media_type = self.TYPES.get(Path(full_path).suffix)
        if media_type is not None:
            response.headers["content-type"] = media_type
        response.headers["cache-control"] = "public, max-age=86400"
        response.headers["x-content-type-options"] = "nosniff"
        return response


def browser_scene(xml_path: Path) -> tuple[str, dict[str, Path]]:
    """The scene ``xml_path`` as the page loads it: its MJCF with every ``file`` renamed, and the map from
    those names to the files on the server; ArtifactError for a missing file or one the page cannot load."""
    root = ET.fromstring(xml_path.read_text())
    for compiler in root.iter("compiler"):
        for attr in ("meshdir", "texturedir", "assetdir"):
            compiler.attrib.pop(attr, None)
    assets: dict[str, Path] = {}
    for element in root.iter():
        source = element.get("file")
        if source is None:
            continue
        path = Path(source)
        suffix = path.suffix.lower()
        if suffix not in ASSET_TYPES or not path.is_absolute() or not path.is_file():
            raise ArtifactError(f"the scene {xml_path.name} names {source!r}, which the page cannot load")
        name = f"asset{len(assets)}{suffix}"
        assets[name] = path
        element.set("file", name)
    return ET.tostring(root, encoding="unicode"), assets
