"""Bakes of materials whose inputs are animated or driven, and Revert, inside `blender -b`.

Run: blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_addon_animation.py -- LIB

The scene is test_addon_bake.py's (test_addon_helpers.baked_scene). Keyframes and drivers on the
Principled's inputs (with their modifiers, NLA strips and driver variables) move to the group
node's and go back on Revert; the Normal Map's Strength is carried the same way; edits on the group
node survive a re-bake and Revert; two materials sharing an action bake and revert independently,
and a copy sharing the action keeps its own edits; an action linked from a library is refused.
"""
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_addon_helpers as h  # noqa: E402


def _ramped_scene(directory):
    """baked_scene, with the Principled's Emission Strength keyed 0 at frame 1 and 10 at frame 11
    (about 5 at frame 6). Returns the material and that input."""
    material = h.baked_scene(directory)
    strength = material.node_tree.nodes["Principled BSDF"].inputs["Emission Strength"]
    for frame, value in ((1, 0.0), (11, 10.0)):
        strength.default_value = value
        strength.keyframe_insert("default_value", frame=frame)
    return material, strength


def test_animated_inputs_keep_animating():
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material, strength = _ramped_scene(directory)
        tree = material.node_tree
        principled = tree.nodes["Principled BSDF"]
        curve = h.tree_fcurves(tree)[0]
        curve.modifiers.new("CYCLES")  # repeats the 1..11 ramp
        driver = principled.inputs["Metallic"].driver_add("default_value").driver
        driver.type = "SCRIPTED"
        driver.expression = "0.25"
        paths_before = sorted(f.data_path for f in h.tree_fcurves(tree))
        drivers_before = sorted(f.data_path for f in tree.animation_data.drivers)
        bpy.ops.wm.save_mainfile()
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        group = tree.nodes["ndfbake"]
        scene = bpy.context.scene
        for frame, expected in ((1, 0.0), (6, 5.0), (11, 10.0), (16, 5.0)):
            scene.frame_set(frame)
            value = group.inputs["Emission Strength"].default_value
            h.expect(abs(value - expected) < 0.6, "Emission Strength at frame %d: %g, expected about %g (the Cycles "
                     "modifier repeats the ramp)" % (frame, value, expected))
        h.expect(abs(group.inputs["Metallic"].default_value - 0.25) < 1e-6, "the driver on Metallic was not carried")
        bake.revert(material)
        h.expect(sorted(f.data_path for f in h.tree_fcurves(tree)) == paths_before,
                 "keyframes after revert: %s" % [f.data_path for f in h.tree_fcurves(tree)])
        h.expect(sorted(f.data_path for f in tree.animation_data.drivers) == drivers_before, "drivers after revert")


def test_edits_on_the_group_node_survive_rebake_and_revert():
    """After a bake the group node holds the material's inputs: a colour set and keyframed there
    is what a re-bake starts from and what Revert leaves on the Principled BSDF."""
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        tree = material.node_tree
        color = tree.nodes["ndfbake"].inputs["Base Color"]
        for frame, green in ((1, 0.5), (11, 1.0)):
            color.default_value = (0.0, green, 0.0, 1.0)
            color.keyframe_insert("default_value", frame=frame)
        bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        scene = bpy.context.scene
        scene.frame_set(11)
        h.expect(tuple(round(c, 3) for c in tree.nodes["ndfbake"].inputs["Base Color"].default_value)
                 == (0.0, 1.0, 0.0, 1.0), "the re-bake lost the colour keyframed on the node")
        bake.revert(material)
        scene.frame_set(1)
        principled = tree.nodes["Principled BSDF"].inputs["Base Color"]
        h.expect(tuple(round(c, 3) for c in principled.default_value) == (0.0, 0.5, 0.0, 1.0),
                 "Revert did not keep the node's keyframed colour: %s" % (tuple(principled.default_value),))


def test_the_normal_maps_strength_is_carried_like_the_principleds_inputs():
    """Normal Strength on the group node stands for the Normal Map's Strength: its keyframes go on
    animating after a bake, an edit on the node survives a re-bake, and Revert leaves the node's
    value and keyframes on the Normal Map."""
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        tree = material.node_tree
        strength = tree.nodes["Normal Map"].inputs["Strength"]
        for frame, value in ((1, 0.0), (11, 1.0)):
            strength.default_value = value
            strength.keyframe_insert("default_value", frame=frame)
        bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        scene = bpy.context.scene
        scene.frame_set(6)
        h.expect(abs(tree.nodes["ndfbake"].inputs["Normal Strength"].default_value - 0.5) < 0.05,
                 "Normal Strength at frame 6: %g, the Normal Map's keyframes give 0.5"
                 % tree.nodes["ndfbake"].inputs["Normal Strength"].default_value)
        for frame, value in ((1, 0.2), (11, 0.4)):  # the user re-keys it on the node
            node_strength = tree.nodes["ndfbake"].inputs["Normal Strength"]
            node_strength.default_value = value
            node_strength.keyframe_insert("default_value", frame=frame)
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        scene.frame_set(11)
        h.expect(abs(tree.nodes["ndfbake"].inputs["Normal Strength"].default_value - 0.4) < 1e-4,
                 "the re-bake lost Normal Strength keyed on the node: %g"
                 % tree.nodes["ndfbake"].inputs["Normal Strength"].default_value)
        bake.revert(material)
        scene.frame_set(1)
        strength = tree.nodes["Normal Map"].inputs["Strength"]
        h.expect(abs(strength.default_value - 0.2) < 1e-4, "Revert left the Normal Map's Strength at %g, not "
                 "the node's 0.2" % strength.default_value)
        paths = sorted(f.data_path for f in h.tree_fcurves(tree))
        h.expect(paths == ['nodes["Normal Map"].inputs[0].default_value'], "keyframes after revert: %s" % paths)


def test_a_keyed_strength_behind_a_muted_link_is_carried():
    """A muted link is no link: the Normal Map's Strength keyframed behind a muted link (its value
    is what renders) animates Normal Strength on the group node (the link carried muted), through a
    re-bake and a failed one, and Revert gives the Normal Map back its link and keyframes exactly."""
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        tree = material.node_tree
        strength = tree.nodes["Normal Map"].inputs["Strength"]
        value = tree.nodes.new("ShaderNodeValue")
        value.outputs[0].default_value = 5.0
        tree.links.new(value.outputs[0], strength).is_muted = True
        for frame, key in ((1, 0.2), (11, 1.0)):
            strength.default_value = key
            strength.keyframe_insert("default_value", frame=frame)
        scene = bpy.context.scene
        scene.frame_set(1)
        bpy.ops.wm.save_mainfile()
        before = h.dump_material(material)
        curves_before = [_curve_state(f) for f in h.tree_fcurves(tree)]

        def check(when):
            node = tree.nodes["ndfbake"]
            socket = node.inputs["Normal Strength"]
            h.expect([(l.from_node, l.is_muted) for l in socket.links] == [(value, True)],
                     "%s: the muted Strength link is not carried muted: %s"
                     % (when, [(l.from_node.name, l.is_muted) for l in socket.links]))
            path = 'nodes["ndfbake"].inputs[%d].default_value' % node.inputs.find("Normal Strength")
            curves = [_curve_state(f)[1:] for f in h.tree_fcurves(tree) if f.data_path == path]
            h.expect(curves == [c[1:] for c in curves_before], "%s: Normal Strength's keyframes %s, the Normal "
                     "Map's %s" % (when, curves, curves_before))
            for frame, expected in ((6, 0.6), (11, 1.0)):
                scene.frame_set(frame)
                h.expect(abs(socket.default_value - expected) < 0.05, "%s: Normal Strength at frame %d: %g, the "
                         "keyframes give %g" % (when, frame, socket.default_value, expected))
            scene.frame_set(1)

        bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        check("after the bake")
        baked = h.dump_material(material)
        h.bake_with_a_bug_in(material, "_wire_group_node", max_lobes=2)
        h.expect(h.dump_material(material) == baked, "the failed re-bake changed the material: %s"
                 % h.differences(baked, h.dump_material(material)))
        check("after a failed re-bake")
        bake.bake_material(material, bake.BakeSettings(max_lobes=2))
        check("after the re-bake")
        bake.revert(material)
        scene.frame_set(1)
        h.expect(h.dump_material(material) == before, "material differs after revert: %s"
                 % h.differences(before, h.dump_material(material)))
        curves = [_curve_state(f) for f in h.tree_fcurves(tree)]
        h.expect(curves == curves_before, "keyframes after revert: %s, before the bake: %s" % (curves, curves_before))

        bake.bake_material(material, bake.BakeSettings(max_lobes=1))  # a key the user moves on the node
        path = 'nodes["ndfbake"].inputs[%d].default_value' % tree.nodes["ndfbake"].inputs.find("Normal Strength")
        h.tree_fcurves(tree).find(path).keyframe_points[1].co.y = 0.6
        bake.revert(material)
        scene.frame_set(11)
        h.expect(abs(strength.default_value - 0.6) < 1e-4, "Revert did not keep the key moved on the node: the "
                 "Normal Map's Strength at frame 11 is %g" % strength.default_value)
        h.expect([l.is_muted for l in strength.links] == [True], "the Strength link after Revert")


def test_two_materials_sharing_an_action_bake_and_revert():
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        first, _ = _ramped_scene(directory)
        second = first.copy()
        h.plane_with(second, "Second")
        bpy.ops.wm.save_mainfile()
        shared = first.node_tree.animation_data.action == second.node_tree.animation_data.action
        print("  the copy shares the action: %s" % shared)
        for material in (first, second):
            bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        bake.revert(first)
        bpy.context.scene.frame_set(6)
        value = second.node_tree.nodes["ndfbake"].inputs["Emission Strength"].default_value
        h.expect(abs(value - 5.0) < 0.6, "reverting the first material stopped the second's animation (%g)" % value)


def test_nla_strips_and_driver_variables_follow_the_inputs():
    """Keyframes in an NLA strip's action (shared with a copy of the material) and a driver
    elsewhere in the tree that reads a Principled input follow the inputs to the group node and
    back: the strip animates the node, the driver reads the node's value, Revert restores the
    paths, and the copy's strip keeps its curves."""
    from ndfbake.shading import blender_compat
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        first, strength = _ramped_scene(directory)
        tree = first.node_tree
        principled = tree.nodes["Principled BSDF"]
        animation = tree.animation_data
        action = animation.action
        strip = animation.nla_tracks.new().strips.new("ramp", 1, action)
        animation.action = None

        def strip_paths():
            slot = blender_compat.animation_slot(strip)
            return sorted(f.data_path for f in blender_compat.action_fcurves(action, slot))
        reader = tree.nodes.new("ShaderNodeValue")
        reader.name = "Reads Metallic"
        driver = reader.outputs[0].driver_add("default_value").driver
        driver.type = "AVERAGE"
        variable = driver.variables.new()
        variable.targets[0].id_type = "MATERIAL"
        variable.targets[0].id = first
        metallic_path = 'node_tree.nodes["Principled BSDF"].inputs[%d].default_value' % principled.inputs.find("Metallic")
        variable.targets[0].data_path = metallic_path
        second = first.copy()
        h.plane_with(second, "Second")
        bpy.ops.wm.save_mainfile()
        h.expect(second.node_tree.animation_data.nla_tracks[0].strips[0].action == action, "the copy shares no strip")
        curves_before = strip_paths()
        for material in (first, second):
            bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        scene = bpy.context.scene
        group = tree.nodes["ndfbake"]
        group.inputs["Metallic"].default_value = 0.75
        scene.frame_set(6)
        for material in (first, second):
            value = material.node_tree.nodes["ndfbake"].inputs["Emission Strength"].default_value
            h.expect(abs(value - 5.0) < 0.6, "%s: the NLA strip does not animate the node (%g)" % (material.name, value))
        h.expect(abs(reader.outputs[0].default_value - 0.75) < 1e-6,
                 "the driver reads %g, not the node's Metallic 0.75" % reader.outputs[0].default_value)
        bake.revert(first)
        scene.frame_set(6)
        h.expect(variable.targets[0].data_path == metallic_path, "Revert left the variable at %s"
                 % variable.targets[0].data_path)
        h.expect(abs(strength.default_value - 5.0) < 0.6, "after Revert the strip does not animate the Principled")
        value = second.node_tree.nodes["ndfbake"].inputs["Emission Strength"].default_value
        h.expect(abs(value - 5.0) < 0.6, "reverting the first material stopped the copy's strip (%g)" % value)
        bake.revert(second)
        h.expect(strip_paths() == curves_before, "the strip's curves after both Reverts: %s" % strip_paths())
        h.expect(not [a for a in bpy.data.actions if a.name.startswith("ndfbake")], "a temporary action was left")


def _curve_state(fcurve):
    return (fcurve.data_path, fcurve.mute, fcurve.lock, fcurve.hide, fcurve.extrapolation,
            [(tuple(k.co), k.type, k.interpolation) for k in fcurve.keyframe_points],
            [(m.type, _envelope_points(m)) for m in fcurve.modifiers])


def _envelope_points(modifier):
    """An Envelope's control points as (frame, min, max), read without touching a point (Blender's
    update on a point's bounds reads past it: node_animation._copy_envelope_points)."""
    points = getattr(modifier, "control_points", ())
    columns = []
    for name in ("frame", "min", "max"):
        values = [0.0] * len(points)
        points.foreach_get(name, values)
        columns.append(values)
    return list(zip(*columns))


def test_curve_settings_and_deletions_on_the_node_survive():
    """A muted, locked, hidden curve with a Breakdown key and two Envelope points is copied with all
    of that (muted on the node too), and comes back the same on Revert; a driver the user removed
    on the group node stays removed on the Principled."""
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material, strength = _ramped_scene(directory)
        tree = material.node_tree
        principled = tree.nodes["Principled BSDF"]
        curve = h.tree_fcurves(tree)[0]
        curve.mute = curve.lock = curve.hide = True
        curve.keyframe_points[1].type = "BREAKDOWN"
        points = curve.modifiers.new("ENVELOPE").control_points
        for frame in (9, 5):
            points.add(frame)
        points.foreach_set("min", (-0.5, -2.0))
        points.foreach_set("max", (0.25, 3.0))
        strength.default_value = 1.0
        principled.inputs["Metallic"].driver_add("default_value").driver.expression = "0.25"
        before = _curve_state(curve)
        bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        node = tree.nodes["ndfbake"]
        bpy.context.scene.frame_set(11)
        h.expect(abs(node.inputs["Emission Strength"].default_value - 1.0) < 1e-6, "the muted curve animates the node")
        node.inputs["Metallic"].driver_remove("default_value")
        node.inputs["Metallic"].default_value = 0.3
        bake.revert(material)
        after = [_curve_state(f) for f in h.tree_fcurves(tree)]
        h.expect(after == [before], "the curve after Revert: %s, before the bake: %s" % (after, before))
        h.expect(not tree.animation_data.drivers, "the driver removed on the node came back")
        h.expect(abs(principled.inputs["Metallic"].default_value - 0.3) < 1e-6, "Metallic was not written back")


def test_a_copy_sharing_the_action_keeps_its_own_edits():
    """Two materials share an action: keys the user sets on one are not overwritten by the other's
    bake-time copies when the other is baked or reverted."""
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        first, _ = _ramped_scene(directory)
        second = first.copy()
        h.plane_with(second, "Second")
        bpy.ops.wm.save_mainfile()
        scene = bpy.context.scene

        def key_fifty(socket):
            socket.default_value = 50.0
            socket.keyframe_insert("default_value", frame=11)
        bake.bake_material(first, bake.BakeSettings(max_lobes=1))
        key_fifty(second.node_tree.nodes["Principled BSDF"].inputs["Emission Strength"])
        bake.revert(first)
        scene.frame_set(1)
        scene.frame_set(11)
        value = second.node_tree.nodes["Principled BSDF"].inputs["Emission Strength"].default_value
        h.expect(abs(value - 50.0) < 1e-4, "reverting the first material undid the copy's key (%g)" % value)
        bake.bake_material(second, bake.BakeSettings(max_lobes=1))
        key_fifty(second.node_tree.nodes["ndfbake"].inputs["Emission Strength"])
        bake.bake_material(first, bake.BakeSettings(max_lobes=1))
        scene.frame_set(1)
        scene.frame_set(11)
        value = second.node_tree.nodes["ndfbake"].inputs["Emission Strength"].default_value
        h.expect(abs(value - 50.0) < 1e-4, "baking the first material undid the copy's key on its node (%g)" % value)


def test_driver_variables_by_socket_name_and_on_the_material_follow():
    """A variable that names the socket and a driver on the material itself read the group node
    while baked and the Principled after Revert; a bake that fails after the node got its inputs
    leaves the variables as they were."""
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        tree = material.node_tree
        tree.nodes["Principled BSDF"].inputs["Metallic"].default_value = 0.25
        reader = tree.nodes.new("ShaderNodeValue")
        variables = []
        for driver in (reader.outputs[0].driver_add("default_value").driver, material.driver_add("roughness").driver):
            driver.type = "SUM"
            variable = driver.variables.new()
            variable.targets[0].id_type = "MATERIAL"
            variable.targets[0].id = material
            variable.targets[0].data_path = 'node_tree.nodes["Principled BSDF"].inputs["Metallic"].default_value'
            variables.append(variable)
        paths = [v.targets[0].data_path for v in variables]
        h.bake_with_a_bug_in(material, "add_eevee_output", max_lobes=1)
        h.expect([v.targets[0].data_path for v in variables] == paths, "the failed bake left %s"
                 % [v.targets[0].data_path for v in variables])
        bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        tree.nodes["ndfbake"].inputs["Metallic"].default_value = 0.75
        bpy.context.scene.frame_set(2)
        h.expect(abs(reader.outputs[0].default_value - 0.75) < 1e-6 and abs(material.roughness - 0.75) < 1e-6,
                 "the drivers read %g and %g, not the node's 0.75" % (reader.outputs[0].default_value,
                                                                    material.roughness))
        bake.revert(material)
        h.expect([v.targets[0].data_path for v in variables] == paths, "Revert left %s"
                 % [v.targets[0].data_path for v in variables])


def test_a_driver_variable_reading_the_strength_follows_it():
    """A variable that reads the Normal Map's Strength reads Normal Strength on the group node while
    baked and the Normal Map's again after Revert, and is left as it was by a bake that fails after
    the node got its inputs, as for the Principled's inputs."""
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        tree = material.node_tree
        reader = tree.nodes.new("ShaderNodeValue")
        driver = reader.outputs[0].driver_add("default_value").driver
        driver.type = "SUM"
        variable = driver.variables.new()
        variable.targets[0].id_type = "MATERIAL"
        variable.targets[0].id = material
        path = 'node_tree.nodes["Normal Map"].inputs["Strength"].default_value'
        variable.targets[0].data_path = path
        h.bake_with_a_bug_in(material, "add_eevee_output", max_lobes=1)
        h.expect(variable.targets[0].data_path == path, "the failed bake left %s" % variable.targets[0].data_path)
        bake.bake_material(material, bake.BakeSettings(max_lobes=1))
        tree.nodes["ndfbake"].inputs["Normal Strength"].default_value = 0.75
        bpy.context.scene.frame_set(2)
        h.expect(abs(reader.outputs[0].default_value - 0.75) < 1e-6, "the driver reads %g, not the node's Normal "
                 "Strength 0.75" % reader.outputs[0].default_value)
        bake.revert(material)
        h.expect(variable.targets[0].data_path == path, "Revert left %s" % variable.targets[0].data_path)


def test_a_linked_action_is_refused():
    """An action linked from a library cannot keep the group node's curves: LINKED_ANIMATION, and
    the material stays as it was."""
    from ndfbake.shading import blender_compat
    from ndfbake.blender import bake
    with h.scratch_dir() as directory:
        material = h.baked_scene(directory)
        action = bpy.data.actions.new("Library Action")
        slot = blender_compat.new_action_slot(action, "NODETREE")
        emission = material.node_tree.nodes["Principled BSDF"].inputs.find("Emission Strength")
        path = 'nodes["Principled BSDF"].inputs[%d].default_value' % emission
        fcurves = blender_compat.action_fcurves(action, slot, create=True)
        curve = blender_compat.new_fcurve(fcurves, path, 0, "")
        curve.keyframe_points.insert(1, 0.0)
        slot_identifier = slot.identifier if slot is not None else None
        library = os.path.join(directory, "library.blend")
        bpy.data.libraries.write(library, {action}, fake_user=True)
        bpy.data.actions.remove(action)
        with bpy.data.libraries.load(library, link=True) as (source, target):
            target.actions = ["Library Action"]
        animation = material.node_tree.animation_data_create()
        animation.action = bpy.data.actions["Library Action"]
        if slot_identifier is not None:  # slotted actions (4.4+): Blender picks no slot no ID has used
            animation.action_slot = animation.action.slots[slot_identifier]
        before = h.dump_material(material)
        e = h.raised(bake.BakeError, lambda: bake.bake_material(material, bake.BakeSettings(max_lobes=1)),
                     "a material animated by a linked action was baked")
        h.expect(e.code == "LINKED_ANIMATION" and "Library Action" in e.message, "%s: %s" % (e.code, e.message))
        h.expect(h.dump_material(material) == before, "the refused bake changed the material")


if __name__ == "__main__":
    h.import_addon()
    h.run([test_animated_inputs_keep_animating, test_edits_on_the_group_node_survive_rebake_and_revert,
           test_the_normal_maps_strength_is_carried_like_the_principleds_inputs,
           test_a_keyed_strength_behind_a_muted_link_is_carried,
           test_two_materials_sharing_an_action_bake_and_revert,
           test_nla_strips_and_driver_variables_follow_the_inputs,
           test_curve_settings_and_deletions_on_the_node_survive,
           test_a_copy_sharing_the_action_keeps_its_own_edits,
           test_driver_variables_by_socket_name_and_on_the_material_follow,
           test_a_driver_variable_reading_the_strength_follows_it, test_a_linked_action_is_refused])
