"""Drawing with Blender's gpu module, in child processes: Blender aborts the whole process when
its GPU start-up fails, and a Vulkan-less process needs its own environment."""
import blender_checks


def test_overlay_draws_projected_box_edges_and_builds_fast():
    done = blender_checks.run_groups("gpu")
    print(next(line for line in done.stdout.splitlines() if line.startswith("overlay batch")))


def test_no_vulkan_is_reported():
    blender_checks.run_groups("no_vulkan", env={"VK_DRIVER_FILES": "/nonexistent/icd.json",
                                                "VK_ICD_FILENAMES": "/nonexistent/icd.json"})
