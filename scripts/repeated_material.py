"""A description package as xacro often writes it: the Unitree Z1 of
example-robot-data with its materials defined twice (a materials file
included twice). Drake's parser refuses the file as written; the cell's
prepared copy keeps the first definition of each and says so in one line.
Writes the copy into OUT, checks that Drake refuses it, then runs it for
20 s on paper_6dof written with only its robot section,
``controller.design: auto`` and the part's position, and prints how the
chamfering force settles (scripts/force_settling.py).

    python scripts/repeated_material.py [OUT]   # default out/repeated_material
"""

from pathlib import Path
import subprocess
import sys

from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant

from deburr_drake.config.cell import package_folder

SCENARIO = """\
name: z1_repeated_material
base: paper_6dof
robot:
  model: {model}
  package_paths: ["pip:example-robot-data/cmeel.prefix/share"]
  flange_frame: link06
  tool_mount: {{rpy: [0.0, 1.5707963, 0.0]}}  # rad: the tool along +x
controller: {{design: auto}}
part:
  pose: {{xyz: [0.35, 0.0, 0.0]}}  # m
"""


def main(argv):
    out = Path(argv[0] if argv else "out/repeated_material").resolve()
    out.mkdir(parents=True, exist_ok=True)
    share = package_folder("pip:example-robot-data/cmeel.prefix/share")
    text = (
        share / "example-robot-data/robots/z1_description/urdf/z1.urdf"
    ).read_text()
    materials = text[
        text.index('  <material name="light_blue">') : text.index("  <gazebo>")
    ]
    model = out / "z1.urdf"
    model.write_text(text.replace(materials, 2 * materials, 1))
    plant = MultibodyPlant(0.0)
    parser = Parser(plant)
    parser.package_map().Add("example-robot-data", share / "example-robot-data")
    try:
        parser.AddModels(str(model))
        sys.exit(f"Drake's parser read {model} as written: nothing to repair")
    except RuntimeError as e:
        print(f"Drake refuses it as written: {str(e).splitlines()[0]}")
    scenario = out / "z1_repeated_material.yaml"
    scenario.write_text(SCENARIO.format(model=model))
    run = out / "run"
    command = ["deburr-drake", "simulate", "--scenario", str(scenario)]
    command += ["--duration", "20", "--out", str(run), "--force"]
    subprocess.run(command, check=True)
    here = Path(__file__).resolve().parent
    subprocess.run(
        [sys.executable, str(here / "force_settling.py"), str(run)], check=True
    )


if __name__ == "__main__":
    main(sys.argv[1:])
