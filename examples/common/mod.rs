//! What the evaluation examples share.

/// The real meshes of the evaluations, paths under `../shared/data/meshes` (all in metres).
/// The first two (YCB's cracker and sugar boxes) have no Panda grasp lying down: wider than
/// its 8 cm from above, and from the side its palm meets the table.
pub const REAL_MESHES: [&str; 12] = [
    "ycb/meshes/003_cracker_box_textured.obj",
    "ycb/meshes/004_sugar_box_textured.obj",
    "ycb/meshes/005_tomato_soup_can_textured.obj",
    "ycb/meshes/006_mustard_bottle_textured.obj",
    "ycb/meshes/009_gelatin_box_textured.obj",
    "ycb/meshes/010_potted_meat_can_textured.obj",
    "dexnet/test/models/bar_clamp.obj",
    "dexnet/meshes/example/box.obj",
    "robosuite/objects/meshes/bottle.obj",
    "robosuite/objects/meshes/can.stl",
    "robosuite/objects/meshes/milk.stl",
    "pybullet/objects/mug.urdf",
];
