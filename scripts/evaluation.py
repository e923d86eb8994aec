"""evaluation.py — what scripts/evaluate and scripts/report share: running idmr and Mitsuba 3
(scripts/mitsuba-render) on a scene and its reductions, and the error measures of their renders
(the paired reduction error of `idmr compare --paired`, RMSE, HDR-FLIP) and the pooling of one
method's errors over its importance seeds.

A Scene keeps its renders and reduced scenes in DIR/<scene name>/; the options it reads from the
script's arguments `a` are output, pixels, iterations, reference_iterations, spp, reference_spp,
photons, importance_iterations, idmr and resume.
"""
import json
import math
import os
import shlex
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
VENV_PYTHON = os.path.join(ROOT, ".venv", "bin", "python")
SEEDS = (1, 2)
REFERENCE_SEED = 1000

# FLIP of an image against a reference, both linear HDR (EXR), on the venv's Python.
FLIP = """
import sys
import flip_evaluator
import mitsuba as mi
import numpy as np
mi.set_variant("scalar_rgb")
test, reference = (np.array(mi.Bitmap(p), dtype=np.float32)[..., :3] for p in sys.argv[1:3])
print(flip_evaluator.evaluate(reference, test, "HDR")[1])
"""


PROGRAM = ["evaluate"]  # the name messages start with: the script that imports this module


def log(message):
    print("%s: %s" % (PROGRAM[0], message), file=sys.stderr, flush=True)


def run(command, capture=False):
    """Runs a command (a list); returns (seconds, stdout). Exits on failure."""
    log("$ " + " ".join("<script>" if "\n" in c else shlex.quote(c) for c in command))
    start = time.monotonic()
    result = subprocess.run(command, stdout=subprocess.PIPE if capture else None, text=True)
    if result.returncode != 0:
        sys.exit("%s: '%s' failed with exit status %d" % (PROGRAM[0], " ".join(command[:2]),
                                                          result.returncode))
    return time.monotonic() - start, result.stdout


def read_json(path):
    with open(path) as f:
        return json.load(f)


def write_atomically(path, text):
    with open(path + ".tmp", "w") as f:
        f.write(text)
    os.replace(path + ".tmp", path)


def scene_name(path):
    stem = os.path.splitext(os.path.basename(path))[0]
    return os.path.basename(os.path.dirname(os.path.abspath(path))) if stem.startswith("scene") \
        else stem


class Scene:
    """One scene of the evaluation: its renders and reductions live in DIR/<name>/."""

    def __init__(self, a, path):
        self.a, self.path, self.name = a, path, scene_name(path)
        self.dir = os.path.join(a.output, self.name)
        os.makedirs(self.dir, exist_ok=True)
        _, out = run([a.idmr, "info", path, "--json", "--no-bvh"], capture=True)
        info = json.loads(out)
        self.vertices = info["vertices"]
        pixels = info["camera"]["width"] * info["camera"]["height"]
        # A path tracer cannot see caustics of a point or spot light (a delta light reached
        # through a specular surface): such scenes are judged by Mitsuba's particle tracer.
        delta_light = any(l["type"] in ("point", "spot") for l in info["lights"])
        specular = any(m["kind"] in ("dielectric", "mirror") for m in info["materials"])
        self.integrator = "ptracer" if delta_light and specular else "path"
        self.resolution = min(1.0, math.sqrt(a.pixels / pixels))
        self.radius = 0.0  # idmr's first gather radius, from the first render

    def render(self, renderer, scene, stem, seed, reference=False, iterations=None):
        """Renders `scene` into DIR/<scene>/<stem>.exr (unless --resume finds it); idmr's report
        of it is DIR/<scene>/<stem>.json. idmr's renders of a scene share the first gather
        radius of the first one (the original, seed 1), so neither the seed nor the reduced
        geometry changes their bias. `iterations` overrides --iterations (idmr)."""
        a, image = self.a, os.path.join(self.dir, stem + ".exr")
        if a.resume and os.path.exists(image):
            if renderer == "idmr" and not self.radius:
                self.radius = read_json(os.path.join(self.dir, stem + ".json"))["first_radius"]
            return image
        if renderer == "idmr":
            command = [a.idmr, "render", scene, "-o", image, "--seed", str(seed), "--quiet",
                       "--resolution", repr(self.resolution), "--iterations",
                       str(iterations or (a.reference_iterations if reference else a.iterations))]
            if self.radius:
                command += ["--radius", repr(self.radius)]
            if a.photons:
                command += ["--photons", str(a.photons)]
        else:
            command = [os.path.join(ROOT, "scripts", "mitsuba-render"), scene, "-o", image,
                       "--seed", str(seed), "--resolution", repr(self.resolution),
                       "--spp", str(a.reference_spp if reference else a.spp),
                       "--integrator", self.integrator]
        run(command, capture=True)
        if renderer == "idmr" and not self.radius:
            self.radius = read_json(os.path.join(self.dir, stem + ".json"))["first_radius"]
        return image

    def reduce(self, spec, target, extra=(), label=None):
        """The reduced scene's directory and report (idmr reduce with the method and options of
        `spec`, method_spec(), and the options `extra`), in DIR/<scene>/<label> (default
        SPEC_LABEL-TARGET)."""
        method, options, spec_label = method_spec(spec)
        a, outdir = self.a, os.path.join(self.dir, label or "%s-%g" % (spec_label, target))
        report = os.path.join(outdir, "report.json")
        if not (a.resume and os.path.exists(report)):
            command = [a.idmr, "reduce", self.path, "--target", repr(target), "--method", method,
                       "-o", outdir, "--force", "--quiet", "--resolution", repr(self.resolution),
                       "--iterations", str(a.importance_iterations)]
            if a.photons:
                command += ["--photons", str(a.photons)]
            run(command + options + list(extra))
        return outdir, read_json(report)


def method_spec(spec):
    """A --methods entry, METHOD[:OPTION=VALUE...] (combined:initial=0.05:passes=2), as the
    `idmr reduce --method` value, the further reduce options it names (["--initial", "0.05",
    "--passes", "2"]) and a label for file names (combined-initial0.05-passes2). A malformed
    option (no '=', empty name or value) raises ValueError naming it."""
    parts = spec.split(":")
    method, options, label = parts[0], [], parts[0]
    if not method:
        raise ValueError("method spec '%s' names no method" % spec)
    for part in parts[1:]:
        name, equals, value = part.partition("=")
        if not equals or not name or not value:
            raise ValueError("method spec '%s': '%s' is not OPTION=VALUE" % (spec, part))
        options += ["--" + name, value]
        label += "-%s%s" % (name, value)
    return method, options, label


def paired(a, images):
    _, out = run([a.idmr, "compare", "--paired", "--json"] + images, capture=True)
    return json.loads(out)


def rmse(a, image, reference):
    _, out = run([a.idmr, "compare", "--json", image, reference], capture=True)
    return json.loads(out)["rmse"]


def flip(image, reference):
    _, out = run([VENV_PYTHON, "-c", FLIP, image, reference], capture=True)
    return float(out.strip())


def pool_draws(measures):
    """One renderer's figures for a method reduced with several importance seeds (`measures`,
    one dict per seed with reduction_mse, mse_standard_error, noisy_rmse, rmse_vs_reference and
    flip): the mean squared error and its root, the error the method makes on average. The
    standard error of the mean is the larger of the seeds' spread (their sample deviation over
    sqrt(n)) and the renders' own (sqrt(sum of squares) / n), and goes to the root as `idmr
    compare` takes it (half the difference of the roots one error above and below); the other
    figures are means."""
    n = len(measures)
    mse = sum(m["reduction_mse"] for m in measures) / n
    render_se = math.sqrt(sum(m["mse_standard_error"] ** 2 for m in measures)) / n
    spread_se = (math.sqrt(sum((m["reduction_mse"] - mse) ** 2 for m in measures) / (n - 1) / n)
                 if n > 1 else 0.0)
    se = max(render_se, spread_se)
    pooled = {
        "reduction_rmse": math.sqrt(mse) if mse > 0 else 0.0,
        "standard_error": 0.5 * (math.sqrt(max(mse + se, 0.0)) - math.sqrt(max(mse - se, 0.0))),
        "reduction_mse": mse,
        "mse_standard_error": se,
    }
    for key in ("noisy_rmse", "rmse_vs_reference", "flip"):
        pooled[key] = sum(m[key] for m in measures) / n
    return pooled
