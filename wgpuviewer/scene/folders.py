"""Material folders, as technical artists download them (ambientCG, Poly Haven): each file's role read from its
name (``file_role``, ``find_material_files``), the TextureRefs a folder gives (``folder_refs``), the note saying
what it gave and left out (``folder_summary``, ``report_folder``), and ``--material DIR`` on a scene's first plane
(``with_folder_material``).
"""

from __future__ import annotations

import logging
import re
import stat
from collections.abc import Collection
from dataclasses import dataclass, replace
from pathlib import Path

from wgpuviewer.core.errors import FileError, InputError, UserError
from wgpuviewer.core.images import link_problem, read_header, resolve_path
from wgpuviewer.core.sidecar import is_recorded
from wgpuviewer.textures import TextureRef

from .limits import texel_coordinate_problem
from .model import Material, Scene

#: The logger of scene notes (the CLIs print its INFO records).
log = logging.getLogger("wgpuviewer.scene")


#: The slots a material folder fills.
FOLDER_SLOTS = ("albedo", "normal", "height")
#: Files a material folder may contribute.
FOLDER_EXTS = (".png", ".jpg", ".jpeg", ".exr", ".tif", ".tiff", ".npy")
#: Name tokens per slot (case-insensitive; names split at non-letters and camel case): ambientCG
#: (NAME_Color, NAME_NormalGL / NAME_NormalDX, NAME_Displacement), Poly Haven (name_diff_1k, name_nor_gl_1k /
#: name_nor_dx_1k, name_disp_1k) and the generic albedo|basecolor|diffuse, normal, height|displacement|disp|bump.
NORMAL_TOKENS = frozenset({"normal", "normals", "normalgl", "normaldx", "nor", "nrm", "norm"})
HEIGHT_TOKENS = frozenset({"height", "heightmap", "displacement", "disp", "bump"})
ALBEDO_TOKENS = frozenset({"albedo", "basecolor", "basecolour", "diffuse", "diff", "color", "colour", "col"})
DIRECTX_TOKENS = frozenset({"dx", "directx", "normaldx"})


def name_tokens(name: str) -> set[str]:
    """Lower-case words of a file stem: split at non-letters/digits and at camel case (NormalGL: normal, gl)."""
    chunks = [c for c in re.split(r"[^A-Za-z0-9]+", name) if c]
    words = {c.lower() for c in chunks}
    for chunk in chunks:
        words.update(w.lower() for w in re.findall(r"[A-Z]+(?![a-z])|[A-Z]?[a-z]+|\d+[A-Za-z]*", chunk))
    return words


def file_role(path: Path) -> tuple[str, str] | None:
    """(slot, normal convention) a material-folder file plays by its name, or None: ("normal", "opengl" |
    "directx"), ("height", ""), ("albedo", ""). Roughness, AO, previews and the like play none."""
    if path.suffix.lower() not in FOLDER_EXTS:
        return None
    words = name_tokens(path.stem)
    if words & NORMAL_TOKENS:
        return "normal", "directx" if words & DIRECTX_TOKENS else "opengl"
    if words & HEIGHT_TOKENS:
        return "height", ""
    if words & ALBEDO_TOKENS:
        return "albedo", ""
    return None


@dataclass(frozen=True)
class FolderFiles:
    """What a material folder holds per slot (None where it has nothing), and its normal map's convention."""

    albedo: Path | None
    normal: Path | None
    normal_y: str
    height: Path | None


def _entry_problem(path: Path) -> str | None:
    """Why a folder entry named like a texture is no file to read (a broken link, a link loop, a folder), or None."""
    problem = link_problem(path)
    if problem is not None:
        return problem
    try:
        mode = path.stat().st_mode
    except OSError as e:
        return f"cannot read ({e.strerror or e})"
    if stat.S_ISDIR(mode):
        return "a folder, not an image file; rename or remove it"
    if not stat.S_ISREG(mode):
        return "not a regular file; replace it with an image file"
    return None


def find_material_files(folder: Path, named: Collection[str] = ()) -> FolderFiles:
    """The material folder's files (``file_role``) for each of FOLDER_SLOTS not in ``named``; the slots in
    ``named`` are those the scene gives next to ``folder`` (they win: the folder is not searched for them, and
    their slots are None here). Where a folder has both an OpenGL and a DirectX normal map (ambientCG ships both),
    the OpenGL one is taken; two candidates for one slot are an error listing them; an entry named for a slot that
    is no readable file (a broken link, a link loop, a folder) is an error naming it, never skipped. Maps
    ``maptools batch`` wrote into the folder (a file with its record ``NAME.json``, ``core.sidecar``) are left out:
    ``X_Displacement.normal.png`` is derived from the height, not the set's normal map. Raises FileError (reason:
    what was found and the fix)."""
    unknown = set(named) - set(FOLDER_SLOTS)
    if unknown:
        raise InputError(f"named {sorted(unknown)}: expected slots among {', '.join(FOLDER_SLOTS)}")
    if not folder.is_dir():
        raise FileError(folder, "not a folder; expected a material folder (e.g. an ambientCG or Poly Haven download)")
    searched = [slot for slot in FOLDER_SLOTS if slot not in named]
    found: dict[str, list[tuple[Path, str]]] = {slot: [] for slot in FOLDER_SLOTS}
    unusable = []
    for path in sorted(folder.iterdir()):
        role = file_role(path)
        if role is None or role[0] not in searched or is_recorded(path):  # maptools' maps are none of the textures
            continue
        problem = _entry_problem(path)
        if problem is None:
            found[role[0]].append((path, role[1]))
        else:
            unusable.append(f"{path.name}: {problem}")
    if unusable:
        raise FileError(folder, "; ".join(unusable))
    gl = [c for c in found["normal"] if c[1] == "opengl"]
    normals = gl or found["normal"]  # OpenGL first: the shader's convention, and ambientCG's NormalGL
    for slot, candidates in (("albedo", found["albedo"]), ("normal", normals), ("height", found["height"])):
        if len(candidates) > 1:
            names = ", ".join(p.name for p, _ in candidates)
            raise FileError(folder, f"{len(candidates)} candidates for the {slot}: {names}; keep one in the folder "
                                    f"or name the file in the scene ({slot} = \"...\")")
    if searched and not any(found.values()):
        slots = " or ".join(filter(None, (", ".join(searched[:-1]), searched[-1])))
        raise FileError(folder, f"no {slots} file recognised by name (expected e.g. "
                                "NAME_Color/NAME_NormalGL/NAME_Displacement, name_diff_1k/name_nor_gl_1k/name_disp_1k, "
                                "or albedo/normal/height)")
    return FolderFiles(albedo=found["albedo"][0][0] if found["albedo"] else None,
                       normal=normals[0][0] if normals else None,
                       normal_y=normals[0][1] if normals else "opengl",
                       height=found["height"][0][0] if found["height"] else None)


def folder_refs(path: Path, where: str, named=()) -> dict:
    """albedo/normal/height TextureRefs (None where absent or ``named``: given by the scene) and normal_y of the
    material folder ``path``; each file's header checked; problems are reported against ``where`` (and the file's
    name)."""
    found = find_material_files(path, named)
    refs: dict = {"normal_y": found.normal_y, "report": f"{where}: {folder_summary(path, found, named)}"}
    for slot in ("albedo", "normal", "height"):
        file = getattr(found, slot)
        refs[slot] = None
        if file is not None:
            try:
                read_header(file)
            except FileError as error:
                raise FileError(path, f"{file.name}: {error.reason}") from None
            refs[slot] = TextureRef("file", path=file, origin=f"{where} ({file.name})")
    return refs


def folder_summary(path: Path, found: FolderFiles, named=()) -> str:
    """What the material folder ``path`` gave each slot (``found``; ``named``: the slots the scene gives itself)
    and every other entry with why it was left out, grouped by reason."""
    picked = []
    for slot in FOLDER_SLOTS:
        file = getattr(found, slot)
        convention = f" ({_CONVENTIONS[found.normal_y]})" if slot == "normal" else ""
        picked.append(f"{slot} {file.name}{convention}" if file is not None
                      else f"{slot} from the scene" if slot in named else f"{slot} none")
    chosen = {getattr(found, slot) for slot in FOLDER_SLOTS}
    ignored: dict[str, list[str]] = {}
    for entry in sorted(path.iterdir()):
        if entry not in chosen:
            ignored.setdefault(_left_out_because(entry, found, named), []).append(entry.name)
    left_out = "; ".join(f"{', '.join(names)} ({why})" for why, names in ignored.items())
    return f"picked {', '.join(picked)}; " + (f"ignored {left_out}" if left_out else "nothing else in the folder")


def _left_out_because(entry: Path, found: FolderFiles, named) -> str:
    """Why the material-folder scan (``find_material_files``) passed over ``entry``."""
    if entry.is_dir():
        return "a folder"
    if entry.suffix.lower() not in FOLDER_EXTS:
        return "not an image file"
    if is_recorded(entry):
        return "written by maptools batch"
    role = file_role(entry)
    if role is None:
        return "no albedo, normal or height in its name"
    if role[0] in named:
        return f"the scene gives the {role[0]}"
    if role[0] == "normal" and role[1] != found.normal_y:
        return f"{_CONVENTIONS[role[1]]} normal map; the {_CONVENTIONS[found.normal_y]} one is used"
    return "not used"


_CONVENTIONS = {"opengl": "OpenGL", "directx": "DirectX"}


#: The folder lines already printed (``report_folder``): once per folder and what it gave.
_REPORTED: set[str] = set()


def report_folder(refs: dict) -> None:
    """Say once what a material folder gave (``folder_refs``' report), as a ``wgpuviewer.scene`` note (INFO): the
    CLIs print those, so the user sees which files ``--material`` or ``folder =`` took and which it left out."""
    if refs["report"] not in _REPORTED:
        _REPORTED.add(refs["report"])
        log.info(refs["report"])


def with_folder_material(scene: Scene, folder: Path) -> Scene:
    """``scene`` with the material folder ``folder`` on its first plane (``--material DIR``): its albedo, normal
    and height files found by name, the plane's relief depth and tiling kept."""
    where = f"--material {folder}"
    plane = next((i for i, o in enumerate(scene.objects) if o.type == "plane"), None)
    if plane is None:
        raise UserError(f"{where}: the scene {scene.path or scene.name} has no plane to show the material on; "
                        "use a scene with a [[objects]] type = \"plane\"")
    try:
        resolved = resolve_path(folder)
        if not resolved.exists():
            raise UserError(f"{where}: folder not found (looked for {resolved})")
        refs = folder_refs(resolved, where)
    except FileError as error:
        raise UserError(f"{where}: {error.reason}") from None
    if refs["albedo"] is None:
        raise UserError(f"{where}: no albedo file (NAME_Color, name_diff_1k, albedo, basecolor or diffuse)")
    old = scene.materials[scene.objects[plane].material]
    problem = texel_coordinate_problem(old.uv_scale, (refs["albedo"], refs["normal"], refs["height"]))
    if problem:
        raise UserError(f"{where}: the scene's uv_scale = {list(old.uv_scale)} is {problem}")
    name = f"folder {folder.name}"
    material = Material(name=name, albedo=refs["albedo"], normal=refs["normal"], normal_y=refs["normal_y"],
                        height=refs["height"], height_scale=old.height_scale, uv_scale=old.uv_scale,
                        uv_offset=old.uv_offset)
    objects = list(scene.objects)
    objects[plane] = replace(objects[plane], material=name)
    report_folder(refs)
    return replace(scene, materials={**scene.materials, name: material}, objects=tuple(objects),
                   name=f"{scene.name} with {folder.name}")
