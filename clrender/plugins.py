"""Importing this module registers every plugin with the scene registry."""
# One import per plugin file: the registry is keyed by the XML (tag, type) each one declares.
from .scene import scene  # noqa: F401
from .shapes import cube, cylinder, disk, instance, obj, ply, rectangle, sdfgrid, serialized, sphere  # noqa: F401
from .cameras import perspective  # noqa: F401
from .filters import box, gaussian, lanczos, mitchell, tent  # noqa: F401
from .films import hdrfilm, ldrfilm  # noqa: F401
from .samplers import independent  # noqa: F401
from .textures import bitmap, checkerboard, checkerboard_color, mesh_attribute, rawconstant, uvtexture  # noqa: F401
from .bsdfs import blendbsdf, bumpmap, conductor, dielectric, diffuse, mask, microfacet, mirror, normalmap  # noqa: F401
from .bsdfs import null, plastic, principled, principledthin  # noqa: F401
from .bsdfs import roughconductor, roughdielectric, roughplastic, thindielectric, twosided  # noqa: F401
from .emitters import area, constant, distant, distantdisk, envmap, point, projector, spot, sunsky  # noqa: F401
from .phase import hg, isotropic  # noqa: F401
from .volumes import constvolume, gridvolume  # noqa: F401
from .media import heterogeneous, homogeneous  # noqa: F401
from .integrators import (ao, aov, av, direct, direct_ems, direct_mats, direct_mis, material,  # noqa: F401
                          moment, normals, path, path_ems, path_mats, path_mis, simple, whitted)
