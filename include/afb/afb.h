#pragma once
// afbullet for games: everything a game needs to load Doom 3 articulated figures and run them as Bullet
// ragdolls in its own world. Link afbullet::afbullet (float Bullet) or afbullet::afbullet_double.
//
//   text::Diagnostics            every message as file:line:col: error|warning: text
//   decl::Library                a content folder (af/, def/, models/) and entity resolution
//   decl::parseAf                an .af text parsed in memory
//   figure::loadEntityFigure     an entity's figure in SI units, with the engine's meaning and findings
//   figure::bodyStatesFromAnimation  body poses and velocities from an md5anim time (start from an animation)
//   figure::bodiesFromJoints     body placements from any md5 pose
//   bullet::Method               how a ragdoll is simulated (presets fast, default, accurate, exact)
//   bullet::RagdollWorld         a method's world-level knobs installed into your btDiscreteDynamicsWorld
//   bullet::RagdollAsset         a figure's shared collision shapes
//   bullet::Ragdoll              one live ragdoll in your world (bullet::spawnOptionsFor: the entity's flags)
//   pose::driveSkeleton          md5 joint transforms from the bodies, by the figure's mod rules
/// \namespace afb
/// Everything afbullet declares, one nested namespace per layer: text, decl, figure, bullet and pose. Each layer
/// uses only the ones before it; Bullet appears in afb::bullet alone.

#include "afb/Version.h"
#include "afb/bullet/Convert.h"
#include "afb/bullet/Method.h"
#include "afb/bullet/Motor.h"
#include "afb/bullet/Ragdoll.h"
#include "afb/bullet/RagdollAsset.h"
#include "afb/bullet/RagdollSolver.h"
#include "afb/bullet/RagdollWorld.h"
#include "afb/decl/AfParser.h"
#include "afb/decl/Library.h"
#include "afb/figure/Figure.h"
#include "afb/figure/Load.h"
#include "afb/figure/Placement.h"
#include "afb/figure/Stabilize.h"
#include "afb/pose/Blend.h"
#include "afb/pose/GetUp.h"
#include "afb/pose/SkeletonDriver.h"
#include "afb/text/Diagnostics.h"
