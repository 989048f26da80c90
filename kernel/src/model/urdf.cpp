// SPDX-License-Identifier: Apache-2.0
#include "model/urdf.hpp"

#include <functional>
#include <map>
#include <set>

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

namespace ubersim::kernel {
namespace fs = std::filesystem;
namespace {

// Collects urdfdom's error messages (it reports through console_bridge) while it parses, and
// restores whatever handler was there before.
class CapturedConsole final : public console_bridge::OutputHandler {
 public:
  CapturedConsole() : previous_(console_bridge::getOutputHandler()) {
    console_bridge::useOutputHandler(this);
  }
  ~CapturedConsole() override { console_bridge::useOutputHandler(previous_); }
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) text_ += (text_.empty() ? "" : "; ") + text;
  }
  const std::string& text() const { return text_; }

 private:
  console_bridge::OutputHandler* previous_;
  std::string text_;
};

Pose ToPose(const urdf::Pose& p) {
  return Pose{Vec3(p.position.x, p.position.y, p.position.z),
              Quat(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).normalized()};
}

// Where an element with a given attribute value stands in the XML, for error messages.
struct XmlIndex {
  TiXmlDocument doc;
  // First element named `tag` whose `attr` equals `value`, searched depth first.
  const TiXmlElement* Find(const char* tag, const char* attr, const std::string& value) const {
    std::function<const TiXmlElement*(const TiXmlElement*)> walk = [&](const TiXmlElement* e) -> const TiXmlElement* {
      for (; e; e = e->NextSiblingElement()) {
        const char* a = e->Attribute(attr);
        if (e->ValueStr() == tag && a && value == a) return e;
        if (const TiXmlElement* found = walk(e->FirstChildElement())) return found;
      }
      return nullptr;
    };
    return walk(doc.RootElement());
  }
};

ModelError ErrorAtElement(const std::string& file, const TiXmlElement* e, const std::string& key,
                          const std::string& reason) {
  return ModelError(file, e ? e->Row() : 0, e ? e->Column() : 0, key, reason);
}

Shape LoadMesh(const fs::path& mesh, const Vec3& scale, const std::string& where_file,
               const TiXmlElement* where, const std::string& key) {
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(
      mesh.string(), aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType);
  if (!scene || !scene->mRootNode) {
    throw ErrorAtElement(where_file, where, key,
                         "cannot read mesh " + mesh.string() + ": " + importer.GetErrorString());
  }
  Shape s;
  s.kind = Shape::Kind::kTriangleMesh;
  // Meshes in the file's root frame; node transforms are applied so a multi-part file stays whole.
  std::function<void(const aiNode*, const aiMatrix4x4&)> add = [&](const aiNode* node, const aiMatrix4x4& parent) {
    const aiMatrix4x4 t = parent * node->mTransformation;
    for (unsigned m = 0; m < node->mNumMeshes; ++m) {
      const aiMesh* mesh_part = scene->mMeshes[node->mMeshes[m]];
      const auto base = static_cast<unsigned>(s.vertices.size());
      for (unsigned v = 0; v < mesh_part->mNumVertices; ++v) {
        const aiVector3D p = t * mesh_part->mVertices[v];
        s.vertices.emplace_back(p.x * scale.x(), p.y * scale.y(), p.z * scale.z());
      }
      for (unsigned f = 0; f < mesh_part->mNumFaces; ++f) {
        const aiFace& face = mesh_part->mFaces[f];
        if (face.mNumIndices != 3) continue;  // points and lines carry no volume
        for (unsigned k = 0; k < 3; ++k) s.indices.push_back(base + face.mIndices[k]);
      }
    }
    for (unsigned c = 0; c < node->mNumChildren; ++c) add(node->mChildren[c], t);
  };
  add(scene->mRootNode, aiMatrix4x4());
  if (s.indices.empty()) {
    throw ErrorAtElement(where_file, where, key, "mesh " + mesh.string() + " has no triangles");
  }
  return s;
}

}  // namespace

UrdfRobot LoadUrdf(const fs::path& file) {
  const std::string f = file.string();
  XmlIndex xml;
  if (!xml.doc.LoadFile(f)) {
    if (xml.doc.ErrorId() == TiXmlBase::TIXML_ERROR_OPENING_FILE) {
      throw ModelError(f, 0, 0, "", "cannot open URDF file");
    }
    throw ModelError(f, xml.doc.ErrorRow(), xml.doc.ErrorCol(), "",
                     std::string("XML error: ") + xml.doc.ErrorDesc());
  }
  std::string text;
  {
    TiXmlPrinter printer;
    xml.doc.Accept(&printer);
    text = printer.CStr();
  }
  urdf::ModelInterfaceSharedPtr model;
  std::string parse_errors;
  {
    CapturedConsole console;
    model = urdf::parseURDF(text);
    parse_errors = console.text();
  }
  if (!model) {
    throw ModelError(f, xml.doc.RootElement() ? xml.doc.RootElement()->Row() : 0,
                     xml.doc.RootElement() ? xml.doc.RootElement()->Column() : 0, "robot",
                     "not a valid URDF robot: " + (parse_errors.empty() ? "urdfdom refused it" : parse_errors));
  }

  UrdfRobot robot;
  robot.file = f;
  const urdf::LinkConstSharedPtr root = model->getRoot();
  // Walk the tree from the root: each link's pose relative to the root with joints at zero.
  std::function<void(const urdf::LinkConstSharedPtr&, const Pose&)> visit =
      [&](const urdf::LinkConstSharedPtr& link, const Pose& pose) {
        const TiXmlElement* link_xml = xml.Find("link", "name", link->name);
        const std::string key = "link '" + link->name + "'";
        UrdfLink out;
        out.name = link->name;
        out.pose = pose;
        if (!link->inertial || !(link->inertial->mass > 0)) {
          throw ErrorAtElement(f, link_xml, key, "every link needs an <inertial> with a positive mass");
        }
        const urdf::Inertial& in = *link->inertial;
        out.inertial_origin = ToPose(in.origin);
        // Inertia given in the inertial frame; express it in a COM frame aligned with the link.
        Eigen::Matrix3d inertia;
        inertia << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
        const Eigen::Matrix3d r = out.inertial_origin.orientation.toRotationMatrix();
        const Eigen::Matrix3d i_link = r * inertia * r.transpose();
        out.mass.mass = in.mass;
        out.mass.inertia_diagonal = Vec3(i_link(0, 0), i_link(1, 1), i_link(2, 2));
        out.mass.inertia_off_diagonal = Vec3(i_link(0, 1), i_link(0, 2), i_link(1, 2));
        out.inertial_origin.orientation = Quat::Identity();
        for (const auto& c : link->collision_array) {
          if (!c || !c->geometry) continue;
          UrdfCollision col;
          col.origin = ToPose(c->origin);
          switch (c->geometry->type) {
            case urdf::Geometry::SPHERE:
              col.shape = Shape::Sphere(static_cast<const urdf::Sphere&>(*c->geometry).radius);
              break;
            case urdf::Geometry::BOX: {
              const auto& d = static_cast<const urdf::Box&>(*c->geometry).dim;
              col.shape = Shape::Box(d.x, d.y, d.z);
              break;
            }
            case urdf::Geometry::CYLINDER: {
              const auto& cy = static_cast<const urdf::Cylinder&>(*c->geometry);
              col.shape = Shape::Cylinder(cy.radius, cy.length);
              break;
            }
            case urdf::Geometry::MESH: {
              const auto& m = static_cast<const urdf::Mesh&>(*c->geometry);
              std::string name = m.filename;
              if (name.rfind("file://", 0) == 0) name = name.substr(7);
              if (name.rfind("package://", 0) == 0) {
                throw ErrorAtElement(f, xml.Find("mesh", "filename", m.filename), key,
                                     "package:// mesh paths need ROS; give a path relative to the URDF file");
              }
              fs::path mesh = name;
              if (mesh.is_relative()) mesh = file.parent_path() / mesh;
              col.shape = LoadMesh(mesh, Vec3(m.scale.x, m.scale.y, m.scale.z), f,
                                   xml.Find("mesh", "filename", m.filename), key);
              break;
            }
          }
          out.collisions.push_back(std::move(col));
        }
        robot.links.push_back(std::move(out));
        for (const auto& joint : link->child_joints) {
          const urdf::LinkConstSharedPtr child = model->getLink(joint->child_link_name);
          UrdfJoint j;
          j.name = joint->name;
          j.parent = link->name;
          j.child = joint->child_link_name;
          j.axis = Vec3(joint->axis.x, joint->axis.y, joint->axis.z);
          switch (joint->type) {
            case urdf::Joint::REVOLUTE:
            case urdf::Joint::CONTINUOUS: j.kind = JointKind::kHinge; break;
            case urdf::Joint::PRISMATIC: j.kind = JointKind::kSlider; break;
            case urdf::Joint::FIXED: j.kind = JointKind::kFixed; break;
            default:
              throw ErrorAtElement(f, xml.Find("joint", "name", joint->name), "joint '" + joint->name + "'",
                                   "joint type not supported (revolute, continuous, prismatic, fixed)");
          }
          if (joint->limits && joint->type != urdf::Joint::CONTINUOUS) {
            j.lower = joint->limits->lower;
            j.upper = joint->limits->upper;
          }
          robot.joints.push_back(j);
          visit(child, pose.Compose(ToPose(joint->parent_to_joint_origin_transform)));
        }
      };
  visit(root, Pose{});
  return robot;
}

}  // namespace ubersim::kernel
