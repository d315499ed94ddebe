"""Drawing with Blender's gpu module, in child processes: Blender aborts the whole process when
its GPU start-up fails, and a Vulkan-less process needs its own environment."""

import blender_checks


def test_overlay_draws_box_edges_each_depth_in_its_colour_and_a_million_boxes():
    done = blender_checks.run_groups("gpu")
    print(next(line for line in done.stdout.splitlines() if line.startswith("colour by depth")))


def test_no_vulkan_is_reported():
    blender_checks.run_groups(
        "no_vulkan", env={"VK_DRIVER_FILES": "/nonexistent/icd.json", "VK_ICD_FILENAMES": "/nonexistent/icd.json"}
    )
