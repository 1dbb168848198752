#pragma once
/// GLSL 3.30 core sources of the preview renderer (internal to render/). The shading chunk is
/// shared by the mesh, particle and ground programs so every surface is lit the same way.
namespace mudcrack::shaders {

/// Shared fragment code: color modes, shadow lookup, the key/fill/rim light rig, tone mapping.
extern const char* const kShadingChunk;

extern const char* const kBackgroundVertex;
extern const char* const kBackgroundFragment;
extern const char* const kMeshVertex;
extern const char* const kMeshFragment;
extern const char* const kMeshShadowVertex;
extern const char* const kSpriteVertex;
extern const char* const kSpriteFragment;
extern const char* const kSpriteShadowVertex;
extern const char* const kSpriteShadowFragment;
extern const char* const kGroundVertex;
extern const char* const kGroundFragment;
extern const char* const kDepthOnlyFragment;

}  // namespace mudcrack::shaders
