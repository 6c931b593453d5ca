"""Prepares copies of Benedikt Bitterli's scenes in Mitsuba form for
bench/mitsuba_import_report.py: SRC/NAME/scene.xml -> DST/bitterli/NAME/scene.xml, each
changed only where the report needs it to be, and every change printed:

- an `<integrator>` that names a plugin of its own (the public copies name
  path_guiding_integrator, restirpt, ...; a `<default name="integrator">` too) becomes
  Mitsuba's `path` with the same maximum depth: the copies' authors changed the
  integrator, Bitterli's files name `path`;
- the film's size (`<default name="resx">` / `resy`, or the film's `width` / `height`) is
  divided by DIV, so that 16 runs of both renderers take minutes, not hours.

Meshes, images and other files the scenes name are not copied (the public copies lack
them): run bench/mitsuba_standins.py DST/bitterli afterwards, as for Mitsuba's own test
scenes. Bitterli's scenes are not stored in this repository.

usage: python bench/bitterli_prepare.py SRC DST [DIV]   (DIV default 4)
"""
import os
import re
import sys

src, dst = sys.argv[1], sys.argv[2]
div = int(sys.argv[3]) if len(sys.argv) > 3 else 4
KNOWN = {"path", "direct", "volpath", "volpathmis", "ptracer", "moment", "aov"}

for name in sorted(os.listdir(src)):
    path = os.path.join(src, name, "scene.xml")
    if not os.path.isfile(path):
        continue
    text = open(path, encoding="utf-8").read()
    changes = []

    def integrator(m):
        block = m.group(0)
        kind = re.search(r'type="([^"]*)"', block).group(1)
        if kind in KNOWN or kind.startswith("$"):
            return block
        depth = re.search(r'name="(?:max_depth|maxDepth)"\s+value="([^"]*)"', block)
        changes.append(f"integrator {kind} -> path")
        inner = f'<integer name="max_depth" value="{depth.group(1)}"/>' if depth else ""
        return f'<integrator type="path">{inner}</integrator>'

    text = re.sub(r"<integrator\b[^>]*?(?:/>|>.*?</integrator>)", integrator, text, flags=re.S)

    def default_integrator(m):
        if m.group(2) in KNOWN:
            return m.group(0)
        changes.append(f"default integrator {m.group(2)} -> path")
        return f'{m.group(1)}path"'

    text = re.sub(r'(<default\s+name="integrator"\s+value=")([^"]*)"', default_integrator, text)

    def size(m):
        old = int(m.group(2))
        changes.append(f"{m.group(1)} {old} -> {old // div}")
        return m.group(0).replace(f'"{old}"', f'"{old // div}"')

    text = re.sub(r'<default\s+name="(resx|resy)"\s+value="(\d+)"', size, text)
    film = re.search(r"<film\b.*?</film>", text, flags=re.S)
    if film:
        block = re.sub(r'<integer\s+name="(width|height)"\s+value="(\d+)"', size, film.group(0))
        text = text[: film.start()] + block + text[film.end():]
    out = os.path.join(dst, "bitterli", name)
    os.makedirs(out, exist_ok=True)
    open(os.path.join(out, "scene.xml"), "w", encoding="utf-8").write(text)
    print(f"{name}: {'; '.join(changes) or 'as it was'}")
