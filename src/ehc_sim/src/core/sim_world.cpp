#include "ehc_sim/sim_world.h"

#include <BulletCollision/CollisionShapes/btShapeHull.h>
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace ehc_sim {

namespace {
[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument("[SimWorld] " + what); }

// Collision filter groups (bits above Bullet's predefined ones).
constexpr int kFloor = 1 << 6;
constexpr int kStatic = 1 << 7;
constexpr int kObject = 1 << 8;
constexpr int kRobot = 1 << 9;

// btCollisionObject user index = kind, user index 2 = index within the kind.
enum Kind { KindFloor = 1, KindScene = 2, KindRobot = 3 };

constexpr btScalar kMargin = 0.001;

btTransform toBt(const Eigen::Isometry3d& T) {
  const Eigen::Quaterniond q(T.linear());
  return btTransform(btQuaternion(q.x(), q.y(), q.z(), q.w()),
                     btVector3(T.translation().x(), T.translation().y(), T.translation().z()));
}

Eigen::Isometry3d toEigen(const btTransform& t) {
  const btQuaternion q = t.getRotation();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z()).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(t.getOrigin().x(), t.getOrigin().y(), t.getOrigin().z());
  return T;
}


constexpr int kMaxHullVertices = 256;  ///< a part's hull with more vertices is resampled (btShapeHull)

/// The convex hull of one part of a mesh (its vertices, interior ones dropped).
std::unique_ptr<btConvexHullShape> hullShape(const TriangleMesh& part) {
  auto hull = std::make_unique<btConvexHullShape>();
  for (const auto& v : part.vertices) hull->addPoint(btVector3(v.x(), v.y(), v.z()), false);
  hull->recalcLocalAabb();
  hull->optimizeConvexHull();
  hull->setMargin(kMargin);
  if (hull->getNumPoints() > kMaxHullVertices) {
    btShapeHull reduced(hull.get());
    reduced.buildHull(kMargin);
    hull = std::make_unique<btConvexHullShape>(&reduced.getVertexPointer()->getX(), reduced.numVertices());
    hull->setMargin(kMargin);
  }
  hull->initializePolyhedralFeatures();
  return hull;
}

/// A box shape with its faces known to Bullet (initializePolyhedralFeatures). A box against a
/// convex hull then collides by separating axes and contact clipping; without the faces (GJK and
/// EPA alone) a 15 mm cube resting on a 5 mm hull disc, or a finger on a cup's floor, sank
/// through it within a few steps. Box against box has an algorithm of its own either way.
std::unique_ptr<btBoxShape> boxShape(const Eigen::Vector3d& half_extents) {
  auto box = std::make_unique<btBoxShape>(btVector3(half_extents.x(), half_extents.y(), half_extents.z()));
  box->setMargin(kMargin);
  box->initializePolyhedralFeatures();
  return box;
}

/// A body's collision shape, in shapes[0] (a compound's children after it). A mesh is a compound
/// of the convex hulls of its connected parts, computed at load. Why hulls of parts: a rigid body
/// rests on a plane on its convex hull, so resting poses on the table are exact; a part that is
/// convex (a box, a bar, a cylinder, a handle segment, a blob) collides exactly, and the library's
/// objects are unions of such parts (a mug's handle is a chain of short cylinders, so the hole
/// stays open; a cup's or bowl's wall is a ring of convex sectors on a base disc, so its inside
/// does). Only the concavity of a single part is filled (a banana's inner curve). Bullet's convex decomposition (HACD, libbullet-extras) was not used: it needs tuning
/// per mesh and seconds per object at load. The hulls' 1 mm collision margin lies outside the
/// triangles (a mesh object rests 1 mm above the table; its depth comes from the triangles).
void makeShapes(const BodyConfig& body, std::vector<std::unique_ptr<btCollisionShape>>* shapes) {
  const Eigen::Vector3d he = body.halfExtents();
  if (body.shape == ShapeType::Mesh) {
    auto compound = std::make_unique<btCompoundShape>();
    std::vector<std::unique_ptr<btCollisionShape>> children;
    for (const TriangleMesh& part : body.mesh->components()) {
      children.push_back(hullShape(part));
      compound->addChildShape(btTransform::getIdentity(), children.back().get());
    }
    shapes->push_back(std::move(compound));
    for (auto& c : children) shapes->push_back(std::move(c));
    return;
  }
  if (body.shape == ShapeType::Box) {
    shapes->push_back(boxShape(he));
    return;
  }
  auto s = std::make_unique<btCylinderShapeZ>(btVector3(he.x(), he.y(), he.z()));
  s->setMargin(kMargin);
  shapes->push_back(std::move(s));
}

/// The surface the depth camera sees: boxes and meshes exactly, cylinders with 96 sides (chord
/// error r (1 - cos(pi / 96)): 0.02 mm on a 70 mm cylinder).
constexpr int kDepthCylinderSides = 96;
std::shared_ptr<const TriangleMesh> depthSurface(const BodyConfig& body) {
  switch (body.shape) {
    case ShapeType::Box: return std::make_shared<const TriangleMesh>(boxSurface(body.size));
    case ShapeType::Cylinder:
      return std::make_shared<const TriangleMesh>(cylinderSurface(body.size.x(), body.size.y(), kDepthCylinderSides));
    case ShapeType::Mesh: return body.mesh;
  }
  return nullptr;
}
}  // namespace

// ---------------------------------------------------------------------------- Bullet state
struct SimWorld::Impl {
  struct Body {
    std::vector<std::unique_ptr<btCollisionShape>> shapes;  // [0] = the body's shape
    std::unique_ptr<btDefaultMotionState> motion;
    std::unique_ptr<btRigidBody> body;
    int group = 0, mask = 0;
  };

  /// Skips robot link pairs that are adjacent or ignored, and the floor for drive links.
  struct PairFilter : public btOverlapFilterCallback {
    const Impl* impl = nullptr;
    bool needBroadphaseCollision(btBroadphaseProxy* p0, btBroadphaseProxy* p1) const override {
      if (!(p0->m_collisionFilterGroup & p1->m_collisionFilterMask) ||
          !(p1->m_collisionFilterGroup & p0->m_collisionFilterMask))
        return false;
      const auto* a = static_cast<const btCollisionObject*>(p0->m_clientObject);
      const auto* b = static_cast<const btCollisionObject*>(p1->m_clientObject);
      if (!a || !b) return true;
      const int ka = a->getUserIndex(), kb = b->getUserIndex();
      if (ka == KindRobot && kb == KindRobot)
        return !impl->ignore[static_cast<std::size_t>(a->getUserIndex2())]
                            [static_cast<std::size_t>(b->getUserIndex2())];
      if (ka == KindRobot && kb == KindFloor) return !impl->floor_link[static_cast<std::size_t>(a->getUserIndex2())];
      if (kb == KindRobot && ka == KindFloor) return !impl->floor_link[static_cast<std::size_t>(b->getUserIndex2())];
      return true;
    }
  };

  std::unique_ptr<btDefaultCollisionConfiguration> configuration;
  std::unique_ptr<btCollisionDispatcher> dispatcher;
  std::unique_ptr<btDbvtBroadphase> broadphase;
  std::unique_ptr<btSequentialImpulseConstraintSolver> solver;
  std::unique_ptr<btDiscreteDynamicsWorld> world;
  PairFilter filter;

  Body floor;
  std::vector<Body> scene;  // SimWorld::bodies_ order
  std::vector<Body> links;  // RobotCollisionModel::links() order
  std::vector<std::string> link_names;
  std::vector<std::vector<bool>> ignore;  // link x link
  std::vector<bool> floor_link;
  std::vector<int> finger_side;  // per link: 0 left, 1 right, -1 not a finger
  std::vector<bool> gripper_link;  // fingers and their parent: may touch objects

  ~Impl() { clear(); }

  void clear() {
    if (world) {
      for (auto* list : {&links, &scene})
        for (auto& b : *list)
          if (b.body) world->removeRigidBody(b.body.get());
      if (floor.body) world->removeRigidBody(floor.body.get());
    }
    links.clear();
    scene.clear();
    floor = Body();
    world.reset();
    solver.reset();
    broadphase.reset();
    dispatcher.reset();
    configuration.reset();
  }

  void add(Body& b, int group, int mask) {
    b.group = group;
    b.mask = mask;
    world->addRigidBody(b.body.get(), group, mask);
  }
};

// ---------------------------------------------------------------------------- construction
namespace {
std::unique_ptr<ehc_control::WholeBodyModel> makeModel(const ehc_control::RobotConfig& r) {
  return std::make_unique<ehc_control::WholeBodyModel>(r);  // reads r.urdf_path
}
}  // namespace

SimWorld::SimWorld(const SimConfig& cfg, const ehc_control::RobotConfig& robot,
                   const SceneConfig& scene)
    : cfg_(cfg),
      robot_cfg_(robot),
      scene_(scene),
      model_(makeModel(robot)),
      collision_model_(std::make_unique<ehc_control::RobotCollisionModel>(model_->urdfXml(), robot.arm_joints)),
      robot_(robot, cfg.fake_robot.noise, cfg.fake_robot.seed, cfg.fake_robot.base_model),
      gripper_(cfg.gripper, collision_model_->fingers().empty()
                                ? 0.035
                                : collision_model_->fingers().front().upper),
      impl_(std::make_unique<Impl>()) {
  cfg_.validate();
  scene_.validate();
  if (collision_model_->fingers().size() != 2)
    fail("the URDF needs exactly two prismatic finger joints (found " +
         std::to_string(collision_model_->fingers().size()) + ")");
  for (const auto& f : collision_model_->fingers())
    if (std::abs(f.upper - gripper_.maxOpening()) > 1e-9)
      fail("the two finger joints must have the same travel");
  dt_ns_ = cfg_.fake_robot.dtNs();
  // robot.yaml's names were checked against the URDF by the WholeBodyModel.
  const auto pairs = ehc_control::selfCollisionIgnorePairs(*model_, *collision_model_, cfg_.collision.self_collision);
  ignored_pairs_.insert(pairs.begin(), pairs.end());
  floor_links_ = robot.floor_links.empty() ? std::vector<std::string>{collision_model_->root()} : robot.floor_links;
  reset(cfg_.fake_robot.seed);
}

SimWorld::~SimWorld() = default;

void SimWorld::setScene(const SceneConfig& scene, unsigned seed) {
  scene.validate();
  scene_ = scene;
  reset(seed);
}

void SimWorld::reset(unsigned seed) {
  robot_.reset(scene_.robot_start, robot_cfg_.arm_ready, seed);
  gripper_.reset();
  step_count_ = 0;
  counters_ = SimCounters();
  report_ = StepReport();
  attached_body_ = -1;
  build();
  placeRobot(robot_.basePose(), robot_.armPositions());
  syncKinematicBodies();
}

void SimWorld::build() {
  Impl& m = *impl_;
  m.clear();
  m.configuration = std::make_unique<btDefaultCollisionConfiguration>();
  m.dispatcher = std::make_unique<btCollisionDispatcher>(m.configuration.get());
  m.broadphase = std::make_unique<btDbvtBroadphase>();
  m.solver = std::make_unique<btSequentialImpulseConstraintSolver>();
  m.world = std::make_unique<btDiscreteDynamicsWorld>(m.dispatcher.get(), m.broadphase.get(),
                                                      m.solver.get(), m.configuration.get());
  m.world->setGravity(btVector3(0, 0, -9.81));
  m.filter.impl = &m;
  m.world->getPairCache()->setOverlapFilterCallback(&m.filter);

  // Floor: infinite static plane z = 0.
  m.floor.shapes.push_back(std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), 0));
  m.floor.motion = std::make_unique<btDefaultMotionState>(btTransform::getIdentity());
  m.floor.body = std::make_unique<btRigidBody>(
      btRigidBody::btRigidBodyConstructionInfo(0, m.floor.motion.get(), m.floor.shapes[0].get()));
  m.floor.body->setFriction(scene_.floor_friction);
  m.floor.body->setUserIndex(KindFloor);
  m.floor.body->setUserIndex2(0);
  m.add(m.floor, kFloor, kObject | kRobot);

  // Scene bodies: table parts, objects, obstacles.
  bodies_ = scene_.bodies();
  first_object_ = static_cast<int>(bodies_.size() - scene_.objects.size() - scene_.obstacles.size());
  m.scene.resize(bodies_.size());
  surfaces_.assign(bodies_.size(), nullptr);
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    const BodyConfig& c = bodies_[i];
    Impl::Body& b = m.scene[i];
    makeShapes(c, &b.shapes);
    surfaces_[i] = depthSurface(c);
    btVector3 inertia(0, 0, 0);
    if (c.mass > 0.0) b.shapes[0]->calculateLocalInertia(c.mass, inertia);
    b.motion = std::make_unique<btDefaultMotionState>(toBt(c.pose()));
    btRigidBody::btRigidBodyConstructionInfo info(c.mass, b.motion.get(), b.shapes[0].get(), inertia);
    info.m_friction = c.friction;
    info.m_rollingFriction = c.mass > 0.0 ? 0.001 : 0.0;
    info.m_linearDamping = 0.05;
    info.m_angularDamping = 0.05;
    b.body = std::make_unique<btRigidBody>(info);
    b.body->setUserIndex(KindScene);
    b.body->setUserIndex2(static_cast<int>(i));
    if (c.mass > 0.0)
      m.add(b, kObject, kFloor | kStatic | kObject | kRobot);
    else
      m.add(b, kStatic, kObject | kRobot);
  }

  // Robot links: kinematic compound bodies.
  const auto& links = collision_model_->links();
  const std::size_t n = links.size();
  m.links.resize(n);
  m.link_names.resize(n);
  m.ignore.assign(n, std::vector<bool>(n, false));
  m.floor_link.assign(n, false);
  m.finger_side.assign(n, -1);
  m.gripper_link.assign(n, false);
  const auto& fingers = collision_model_->fingers();
  for (std::size_t i = 0; i < n; ++i) {
    const ehc_control::RobotLinkGeometry& g = links[i];
    m.link_names[i] = g.name;
    auto compound = std::make_unique<btCompoundShape>();
    Impl::Body& b = m.links[i];
    for (const ehc_control::CollisionShape& s : g.shapes) {
      std::unique_ptr<btCollisionShape> child;
      switch (s.type) {
        case ehc_control::CollisionShape::Type::Box:
          child = boxShape(s.halfExtents());
          break;
        case ehc_control::CollisionShape::Type::Cylinder: {
          const Eigen::Vector3d h = s.halfExtents();
          child = std::make_unique<btCylinderShapeZ>(btVector3(h.x(), h.y(), h.z()));
          break;
        }
        case ehc_control::CollisionShape::Type::Sphere:
          child = std::make_unique<btSphereShape>(s.size.x());
          break;
      }
      if (s.type != ehc_control::CollisionShape::Type::Sphere) child->setMargin(kMargin);
      compound->addChildShape(toBt(s.origin), child.get());
      b.shapes.push_back(std::move(child));
    }
    b.shapes.insert(b.shapes.begin(), std::move(compound));
    b.motion = std::make_unique<btDefaultMotionState>(btTransform::getIdentity());
    b.body = std::make_unique<btRigidBody>(
        btRigidBody::btRigidBodyConstructionInfo(0, b.motion.get(), b.shapes[0].get()));
    b.body->setCollisionFlags(b.body->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
    b.body->setActivationState(DISABLE_DEACTIVATION);
    b.body->setUserIndex(KindRobot);
    b.body->setUserIndex2(static_cast<int>(i));
    for (std::size_t f = 0; f < fingers.size(); ++f) {
      if (fingers[f].child_link == g.name) {
        m.finger_side[i] = static_cast<int>(f);
        m.gripper_link[i] = true;
      }
      if (fingers[f].parent_link == g.name) m.gripper_link[i] = true;
    }
    m.floor_link[i] = std::find(floor_links_.begin(), floor_links_.end(), g.name) != floor_links_.end();
  }
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j) {
      const std::string &a = links[i].name, &b = links[j].name;
      m.ignore[i][j] = i == j || ignored_pairs_.count(a < b ? ehc_control::LinkPair{a, b} : ehc_control::LinkPair{b, a}) > 0;
    }
  for (std::size_t i = 0; i < n; ++i) m.add(m.links[i], kRobot, kFloor | kStatic | kObject | kRobot);
}

// ---------------------------------------------------------------------------- kinematics
Eigen::Isometry3d SimWorld::linkPose(const std::string& link) const {
  return model_->fk(robot_.basePose(), robot_.armPositions(), link) *
         collision_model_->fingerOffset(link, gripper_.opening());
}

Eigen::Isometry3d SimWorld::linkPoseInParent(const std::string& link) const {
  const std::string& parent = collision_model_->parentOf(link);
  if (parent.empty()) return Eigen::Isometry3d::Identity();
  const Eigen::VectorXd& q = robot_.armPositions();
  return model_->linkPoseInBase(q, parent).inverse() *
         (model_->linkPoseInBase(q, link) * collision_model_->fingerOffset(link, gripper_.opening()));
}

Eigen::Isometry3d SimWorld::cameraPose() const { return linkPose(robot_cfg_.camera_frame); }

Eigen::Isometry3d SimWorld::linkBodyPose(const std::string& link) const {
  for (std::size_t i = 0; i < impl_->link_names.size(); ++i)
    if (impl_->link_names[i] == link) return toEigen(impl_->links[i].body->getWorldTransform());
  fail("link '" + link + "' has no collision body");
}

Eigen::Isometry3d SimWorld::bodyPose(int i) const {
  if (i < 0 || i >= static_cast<int>(bodies_.size())) fail("body index out of range");
  return toEigen(impl_->scene[static_cast<std::size_t>(i)].body->getWorldTransform());
}

Eigen::Isometry3d SimWorld::tagPose(int i) const {
  if (!bodies_.at(static_cast<std::size_t>(i)).tag.enabled) fail("body '" + bodies_[static_cast<std::size_t>(i)].name + "' has no tag");
  return bodyPose(i) * tagPoseInBody(bodies_[static_cast<std::size_t>(i)]);
}

void SimWorld::placeRobot(const Eigen::Vector3d& base, const Eigen::VectorXd& q) {
  Impl& m = *impl_;
  const Eigen::Isometry3d Twb = ehc_control::WholeBodyModel::baseTransform(base);
  const auto& links = collision_model_->links();
  Eigen::Isometry3d gripper_pose = Eigen::Isometry3d::Identity();
  const std::string& gripper_link = collision_model_->fingers().front().parent_link;
  for (std::size_t i = 0; i < links.size(); ++i) {
    const Eigen::Isometry3d T = Twb * model_->linkPoseInBase(q, links[i].name) *
                                collision_model_->fingerOffset(links[i].name, gripper_.opening());
    m.links[i].motion->setWorldTransform(toBt(T));
    if (links[i].name == gripper_link) gripper_pose = T;
  }
  if (attached_body_ >= 0) {
    if (gripper_pose.matrix() == Eigen::Matrix4d::Identity())
      gripper_pose = Twb * model_->linkPoseInBase(q, gripper_link);
    m.scene[static_cast<std::size_t>(attached_body_)].motion->setWorldTransform(
        toBt(gripper_pose * held_in_gripper_));
  }
}

void SimWorld::setRobotState(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q) {
  robot_.reset(base_pose, q, 0);  // positions only; noise stream restarts (tests and tools)
  placeRobot(robot_.basePose(), robot_.armPositions());
  syncKinematicBodies();
}

void SimWorld::syncKinematicBodies() {
  // Kinematic bodies otherwise read their motion state only at the next step; setting the
  // interpolation transform too gives them zero velocity (a teleport, not a motion).
  for (auto* list : {&impl_->links, &impl_->scene})
    for (auto& b : *list)
      if (b.body->isKinematicObject()) {
        btTransform t;
        b.motion->getWorldTransform(t);
        b.body->setWorldTransform(t);
        b.body->setInterpolationWorldTransform(t);
      }
  impl_->world->updateAabbs();
}

// ---------------------------------------------------------------------------- stepping
void SimWorld::collectContacts(StepReport* report, std::set<int>* left,
                               std::set<int>* right) const {
  const Impl& m = *impl_;
  const double tol = cfg_.collision.tolerance;
  const double touch = cfg_.gripper.contact_tolerance;
  const int nm = m.dispatcher->getNumManifolds();
  for (int k = 0; k < nm; ++k) {
    const btPersistentManifold* man = m.dispatcher->getManifoldByIndexInternal(k);
    const int np = man->getNumContacts();
    if (np == 0) continue;
    const btCollisionObject* a = man->getBody0();
    const btCollisionObject* b = man->getBody1();
    bool swapped = false;
    if (a->getUserIndex() != KindRobot) {
      std::swap(a, b);
      swapped = true;
    }
    if (a->getUserIndex() != KindRobot) continue;  // world-world contact: plain physics
    int deepest = 0;
    for (int p = 1; p < np; ++p)
      if (man->getContactPoint(p).getDistance() < man->getContactPoint(deepest).getDistance()) deepest = p;
    const btManifoldPoint& pt = man->getContactPoint(deepest);
    const double d = pt.getDistance();
    const btVector3 pos = swapped ? pt.getPositionWorldOnB() : pt.getPositionWorldOnA();
    const std::size_t la = static_cast<std::size_t>(a->getUserIndex2());
    CollisionContact c;
    c.a = m.link_names[la];
    c.distance = d;
    c.point = Eigen::Vector3d(pos.x(), pos.y(), pos.z());
    bool collision = false;
    switch (b->getUserIndex()) {
      case KindRobot: {
        const std::size_t lb = static_cast<std::size_t>(b->getUserIndex2());
        if (m.ignore[la][lb]) break;
        c.b = m.link_names[lb];
        c.self = true;
        collision = d < -tol;
        break;
      }
      case KindFloor:
        if (m.floor_link[la]) break;
        c.b = "floor";
        collision = d < -tol;
        break;
      case KindScene: {
        const int bi = b->getUserIndex2();
        const BodyConfig& body = bodies_[static_cast<std::size_t>(bi)];
        c.b = body.name;
        if (bi == attached_body_) break;
        if (body.mass > 0.0 && m.gripper_link[la]) {
          const int object = bi - first_object_;
          if (d < touch && m.finger_side[la] == 0) left->insert(object);
          if (d < touch && m.finger_side[la] == 1) right->insert(object);
          break;  // the gripper may touch objects
        }
        collision = d < -tol;
        break;
      }
      default:
        break;
    }
    if (!collision) continue;
    if (c.self) report->self_collision = true;
    else report->robot_world_collision = true;
    bool merged = false;
    for (auto& e : report->collisions)
      if (e.a == c.a && e.b == c.b) {
        if (c.distance < e.distance) e = c;
        merged = true;
      }
    if (!merged) report->collisions.push_back(c);
  }
}

StepReport SimWorld::checkCollisions() {
  impl_->world->performDiscreteCollisionDetection();
  StepReport r;
  std::set<int> l, rr;
  collectContacts(&r, &l, &rr);
  return r;
}

const StepReport& SimWorld::step(const Eigen::VectorXd& command) {
  Impl& m = *impl_;
  // Release a held object the gripper let go of (open command since the last step).
  if (attached_body_ >= 0 && gripper_.heldObject() < 0) {
    Impl::Body& b = m.scene[static_cast<std::size_t>(attached_body_)];
    const BodyConfig& c = bodies_[static_cast<std::size_t>(attached_body_)];
    m.world->removeRigidBody(b.body.get());
    b.body->setCollisionFlags(b.body->getCollisionFlags() & ~btCollisionObject::CF_KINEMATIC_OBJECT);
    btVector3 inertia(0, 0, 0);
    b.shapes[0]->calculateLocalInertia(c.mass, inertia);
    b.body->setMassProps(c.mass, inertia);
    b.body->updateInertiaTensor();
    b.body->setLinearVelocity(btVector3(0, 0, 0));
    b.body->setAngularVelocity(btVector3(0, 0, 0));
    b.body->forceActivationState(ACTIVE_TAG);
    m.add(b, b.group, b.mask);
    attached_body_ = -1;
  }

  const Eigen::Vector3d b0 = robot_.basePose();
  const Eigen::VectorXd q0 = robot_.armPositions();
  robot_.step(command, cfg_.fake_robot.dt);  // validates the command
  const Eigen::Vector3d b1 = robot_.basePose();
  const Eigen::VectorXd q1 = robot_.armPositions();
  const double dyaw = std::remainder(b1.z() - b0.z(), 2.0 * M_PI);

  report_ = StepReport();
  const int k = cfg_.substeps();
  const double h = cfg_.fake_robot.dt / k;
  const std::string& gripper_link = collision_model_->fingers().front().parent_link;
  for (int s = 1; s <= k; ++s) {
    const double a = static_cast<double>(s) / k;
    Eigen::Vector3d base = b0 + a * (b1 - b0);
    base.z() = s == k ? b1.z() : b0.z() + a * dyaw;
    const Eigen::VectorXd q = s == k ? q1 : Eigen::VectorXd(q0 + a * (q1 - q0));
    gripper_.advance(h);
    placeRobot(base, q);
    m.world->stepSimulation(static_cast<btScalar>(h), 0);
    std::set<int> left, right;
    collectContacts(&report_, &left, &right);
    if (gripper_.onFingerContacts(left, right)) {
      // Attach: the object becomes kinematic and follows the gripper from now on.
      attached_body_ = objectBodyIndex(gripper_.heldObject());
      Impl::Body& b = m.scene[static_cast<std::size_t>(attached_body_)];
      const Eigen::Isometry3d Tg = ehc_control::WholeBodyModel::baseTransform(base) *
                                   model_->linkPoseInBase(q, gripper_link);
      held_in_gripper_ = Tg.inverse() * toEigen(b.body->getWorldTransform());
      m.world->removeRigidBody(b.body.get());
      b.body->setMassProps(0, btVector3(0, 0, 0));
      b.body->setLinearVelocity(btVector3(0, 0, 0));
      b.body->setAngularVelocity(btVector3(0, 0, 0));
      b.body->setCollisionFlags(b.body->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
      b.body->setActivationState(DISABLE_DEACTIVATION);
      m.add(b, b.group, b.mask);
    }
  }
  if (gripper_.heldObject() >= 0) gripper_.onHeldObjectHeight(objectPose(gripper_.heldObject()).translation().z());

  ++step_count_;
  ++counters_.steps;
  if (report_.robot_world_collision) ++counters_.collision_steps;
  if (report_.self_collision) ++counters_.self_collision_steps;
  return report_;
}

}  // namespace ehc_sim
