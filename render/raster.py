"""A minimal OpenGL 3.3 rasteriser for pre-shaded triangle soups, many cameras per pass.

One vertex buffer holds the room and every person (people at their origin); one
uniform array moves the people, so nothing is re-uploaded when they walk. Each camera
draws into its own horizontal band of a tall framebuffer (RGBA8 + depth), upside
down so that ``glReadPixels`` returns rows top first, and one ``glReadPixels`` reads
all its cameras at once into a preallocated ``(n_cams, H, W, 4)`` array. A framebuffer
(a *page*) holds as many bands as the OpenGL implementation's size limit allows
(16384 rows on llvmpipe: 31 lab canvases); more cameras take more pages, each drawn
and read in turn, band b being band ``b % per_page`` of page ``b // per_page``: RGB is the baked
vertex colour, interpolated across the triangle; alpha is the exact label (person
index + 1, 0 for the room), written from a ``flat`` varying. No lighting, no MSAA, no
blending. The people's back faces are culled (:meth:`Rasteriser._draw_range`),
except for the cameras a person comes within the near plane of or encloses (``near``),
which draw them unclipped by the near plane; the room's faces are all drawn.

:meth:`Rasteriser.draw` draws everything (the room, the benchmark floor, the tests'
reference). The renderer's steps use :meth:`Rasteriser.draw_people`: a copy of the
room's colour and depth (:meth:`Rasteriser.store_room`, taken once) is blitted into
each person's canvas box, only the people's triangles (the tail of the vertex buffer)
are drawn, and only those boxes are read. Starting from the room's own depth buffer
makes it exact: a person fragment passes or fails exactly as in a whole-scene draw,
including the floor-level pixels of the feet where the person and the floor tie in
24-bit depth (there the floor, drawn first, wins under ``GL_LESS``); a plain clear
instead of the room's depth got ~2 such pixels per 16-camera step wrong.

The context comes from :func:`render.gl.context` (one per process, shared).
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass

import numpy as np

from . import gl
from .geometry import Mesh

VERTEX_SHADER = """#version 330 core
layout(location = 0) in vec3 position;   // metres, world frame (people: at their feet)
layout(location = 1) in vec3 colour;     // shaded RGB in [0, 1]
layout(location = 2) in float person;    // person index, -1 for the room
uniform mat4 view_proj;
uniform vec2 offsets[%(n)d];             // people's floor positions, metres
out vec3 v_colour;
flat out float v_label;
void main() {
    vec3 p = position;
    if (person >= 0.0) p.xy += offsets[int(person)];
    gl_Position = view_proj * vec4(p, 1.0);
    v_colour = colour;
    v_label = (person + 1.0) / 255.0;
}
"""

FRAGMENT_SHADER = """#version 330 core
in vec3 v_colour;
flat in float v_label;
out vec4 frag;
void main() { frag = vec4(v_colour, v_label); }
"""

#: Where a hidden person is moved (far outside every frustum).
HIDDEN = 1.0e6


#: The most people a frame can label: uint8 labels, 0 the background and 255 reserved.
MAX_PEOPLE = 254


@dataclass
class Page:
    """One framebuffer: bands ``first .. first + tiles - 1``, band ``first`` at the bottom.

    fbo, colour (texture), depth (renderbuffer) : what is drawn into
    room_fbo, room_colour, room_depth : the room's copy (:meth:`Rasteriser.store_room`)
    """

    first: int
    tiles: int
    fbo: int
    colour: int
    depth: int
    room_fbo: int | None = None
    room_colour: int | None = None
    room_depth: int | None = None


class Rasteriser:
    """Draws ``mesh`` for up to ``n_tiles`` cameras of ``width`` x ``height`` pixels per pass.

    mesh : the room and the people (:class:`render.geometry.Mesh`), the room's vertices first
    n_people : how many people the mesh holds (size of the offsets uniform)
    near_only : how many of the mesh's last vertices (the people's soles) are drawn only
        for the cameras flagged ``near`` (:meth:`_draw_range`)
    """

    #: Cull the people's back faces (see :meth:`_draw_range`); False draws both (tests).
    cull_back_faces = True

    #: Rows of one framebuffer (page) at most; None: the OpenGL implementation's limit
    #: (``GL_MAX_RENDERBUFFER_SIZE``, ``GL_MAX_TEXTURE_SIZE``). Tests lower it to page.
    max_page_height: int | None = None

    def __init__(self, mesh: Mesh, n_people: int, width: int, height: int, n_tiles: int,
                 backend: str = "egl", near_only: int = 0):
        if n_people > MAX_PEOPLE:
            raise ValueError(f"people.count: expected at most {MAX_PEOPLE} people (uint8 labels), got {n_people}")
        self.backend, GL = gl.context(backend)
        self.GL = GL
        self.width, self.height, self.n_tiles = int(width), int(height), int(n_tiles)
        self.n_people = int(n_people)
        self.n_vertices = len(mesh.positions)
        room = np.asarray(mesh.person) < 0
        self.people_first = int(np.argmin(room)) if not room.all() else self.n_vertices
        if room[self.people_first:].any():
            raise ValueError("mesh: expected the room's vertices first, then the people's")
        self.near_only = int(near_only)
        if not 0 <= self.near_only <= self.n_vertices - self.people_first:
            raise ValueError(f"near_only: expected 0..{self.n_vertices - self.people_first} of the people's "
                             f"vertices, got {near_only}")
        self.pages: list[Page] = []
        self._build_program(GL)
        self._build_buffers(GL, mesh)
        self._build_pages(GL)
        self.pixels = np.empty((self.n_tiles, self.height, self.width, 4), np.uint8)

    def _build_program(self, GL) -> None:
        from OpenGL.GL import shaders

        vs = shaders.compileShader(VERTEX_SHADER % {"n": max(1, self.n_people)}, GL.GL_VERTEX_SHADER)
        fs = shaders.compileShader(FRAGMENT_SHADER, GL.GL_FRAGMENT_SHADER)
        self.program = shaders.compileProgram(vs, fs, validate=False)
        GL.glDeleteShader(vs)
        GL.glDeleteShader(fs)
        self._u_view_proj = GL.glGetUniformLocation(self.program, "view_proj")
        self._u_offsets = GL.glGetUniformLocation(self.program, "offsets")

    def _build_buffers(self, GL, mesh: Mesh) -> None:
        data = np.ascontiguousarray(np.column_stack([mesh.positions, mesh.colours, mesh.person]),
                                    dtype=np.float32)
        self.vao = GL.glGenVertexArrays(1)
        GL.glBindVertexArray(self.vao)
        self.vbo = GL.glGenBuffers(1)
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, self.vbo)
        GL.glBufferData(GL.GL_ARRAY_BUFFER, data.nbytes, data, GL.GL_STATIC_DRAW)
        stride = data.shape[1] * 4
        for loc, (start, size) in enumerate(((0, 3), (3, 3), (6, 1))):
            GL.glEnableVertexAttribArray(loc)
            GL.glVertexAttribPointer(loc, size, GL.GL_FLOAT, GL.GL_FALSE, stride, ctypes.c_void_p(start * 4))
        GL.glBindVertexArray(0)

    def _build_pages(self, GL) -> None:
        limit = min(int(GL.glGetIntegerv(GL.GL_MAX_RENDERBUFFER_SIZE)),
                    int(GL.glGetIntegerv(GL.GL_MAX_TEXTURE_SIZE)))
        rows = limit if self.max_page_height is None else min(limit, int(self.max_page_height))
        if self.width > limit or self.height > rows:
            raise ValueError(f"cameras.intrinsics.resolution: a canvas of {self.width}x{self.height} pixels "
                             f"(the image and its distortion margin) exceeds this OpenGL's limit of {rows}")
        self.per_page = rows // self.height
        for first in range(0, self.n_tiles, self.per_page):
            self._add_page(GL, first, min(self.per_page, self.n_tiles - first))

    def _add_page(self, GL, first: int, tiles: int) -> None:
        height = self.height * tiles
        fbo = GL.glGenFramebuffers(1)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, fbo)
        colour = _texture(GL, GL.GL_RGBA8, self.width, height, GL.GL_RGBA, GL.GL_UNSIGNED_BYTE, None,
                          GL.GL_LINEAR)
        GL.glFramebufferTexture2D(GL.GL_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, GL.GL_TEXTURE_2D, colour, 0)
        depth = GL.glGenRenderbuffers(1)
        self.pages.append(Page(first, tiles, fbo, colour, depth))
        GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, depth)
        GL.glRenderbufferStorage(GL.GL_RENDERBUFFER, GL.GL_DEPTH_COMPONENT24, self.width, height)
        GL.glFramebufferRenderbuffer(GL.GL_FRAMEBUFFER, GL.GL_DEPTH_ATTACHMENT, GL.GL_RENDERBUFFER, depth)
        status = GL.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, 0)
        if status != GL.GL_FRAMEBUFFER_COMPLETE:
            raise RuntimeError(f"OpenGL framebuffer incomplete (status 0x{int(status):x})")

    def _by_page(self, bands: np.ndarray) -> list[tuple[Page, np.ndarray]]:
        """The pages ``bands`` fall in, each with the indices k (in order) of its bands."""
        page = bands // self.per_page
        return [(self.pages[p], np.flatnonzero(page == p)) for p in np.unique(page)]

    def draw(self, view_projs: np.ndarray, offsets_xy: np.ndarray, read: bool = True,
             bands=None, near=None) -> np.ndarray:
        """Draw every camera's ideal canvas and (with ``read``) read the pixels back.

        view_projs : (n, 4, 4) float, projection @ view per camera, n <= n_tiles
        offsets_xy : (n_people, 2) float, metres, world frame (NaN rows: hidden)
        bands : (n,) distinct ints in [0, n_tiles), the framebuffer band each camera is
            drawn in (default 0..n-1); only those bands are cleared and read. A camera
            always drawn in the same band gives bit-identical pixels wherever the scene
            is the same (the renderer relies on it to reuse its cached background).
        near : (n,) bool, the cameras a person may come within the near plane of (or
            enclose): their people are drawn with back faces and without near clipping
            (:meth:`_draw_range`); default none
        Returns (n, H, W, 4) uint8, rows top first: RGB and the label in alpha. Band b is
        read into ``self.pixels[b]`` (the result is a view of it when the bands are
        consecutive): it is reused by the next call that reads band b, copy what you keep.
        """
        GL = self.GL
        n = len(view_projs)
        if not 1 <= n <= self.n_tiles:
            raise ValueError(f"view_projs: expected 1..{self.n_tiles} cameras, got {n}")
        bands = self._check_bands(np.arange(n) if bands is None else bands, n)
        near = _flags(near, n)
        gl.context(self.backend)
        vp = np.ascontiguousarray(view_projs, np.float32)
        for page, ks in self._by_page(bands):
            local = bands[ks] - page.first
            self._draw_page(GL, page, vp[ks], offsets_xy, local, near[ks], read)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, 0)
        if not read:
            return None
        b0 = int(bands[0])
        if np.array_equal(bands, np.arange(b0, b0 + n)):
            return self.pixels[b0:b0 + n]
        return self.pixels[bands]

    def _check_bands(self, bands, n: int) -> np.ndarray:
        """``bands`` as (n,) ints, refused unless n distinct band numbers in ``0 .. n_tiles - 1``."""
        bands = np.asarray(bands, int).reshape(-1)
        if len(bands) != n or len(set(bands.tolist())) != n or (n and (bands.min() < 0 or bands.max() >= self.n_tiles)):
            raise ValueError(f"bands: expected {n} distinct band numbers in 0..{self.n_tiles - 1}, got {bands}")
        return bands

    def _draw_page(self, GL, page: Page, vp: np.ndarray, offsets_xy, local: np.ndarray, near: np.ndarray,
                   read: bool) -> None:
        """:meth:`draw` of the cameras whose bands are ``local`` (bands of ``page``)."""
        l0 = int(local[0])
        consecutive = np.array_equal(local, np.arange(l0, l0 + len(local)))
        self._state(GL, page)
        self._set_offsets(GL, offsets_xy)
        GL.glClearColor(0.0, 0.0, 0.0, 0.0)
        if consecutive and len(local) == page.tiles:
            GL.glDisable(GL.GL_SCISSOR_TEST)
            GL.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT)
        else:                                       # clear only the bands drawn now
            GL.glEnable(GL.GL_SCISSOR_TEST)
            runs = [(l0, len(local))] if consecutive else [(int(b), 1) for b in local]
            for start, count in runs:
                GL.glScissor(0, start * self.height, self.width, count * self.height)
                GL.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT)
            GL.glDisable(GL.GL_SCISSOR_TEST)
        # every camera's room, then every camera's people: the bands are disjoint, so each
        # camera still gets its room before its people
        self._draw_range(GL, vp, local, 0, self.people_first)
        self._draw_range(GL, vp, local, self.people_first, self.n_vertices - self.people_first, cull=True,
                         near=near, near_only=self.near_only)
        if not read:
            return
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        GL.glReadBuffer(GL.GL_COLOR_ATTACHMENT0)
        if consecutive:                             # one read for all the page's cameras
            GL.glReadPixels(0, l0 * self.height, self.width, self.height * len(local), GL.GL_RGBA,
                            GL.GL_UNSIGNED_BYTE, self.pixels[page.first + l0:page.first + l0 + len(local)])
        else:
            for b in local:
                GL.glReadPixels(0, int(b) * self.height, self.width, self.height, GL.GL_RGBA,
                                GL.GL_UNSIGNED_BYTE, self.pixels[page.first + int(b)])

    def _draw_range(self, GL, view_projs: np.ndarray, bands, first: int, count: int,
                    cull: bool = False, near=None, near_only: int = 0) -> None:
        """Draw vertices ``first .. first + count`` once per camera, camera k in band ``bands[k]``.

        cull : cull back faces (for the people's triangles; with :attr:`cull_back_faces`).
        A person (:func:`render.geometry.cylinder`) is a closed convex surface for every
        camera above the floor and outside it (its open bottom faces the floor), so a back
        face's fragment always lies behind a front face's at the same pixel: culling the back faces leaves every covered pixel and label as it
        was, and llvmpipe rasterises ~40 % fewer triangles (the side's far half). Only
        where a front and a back face tie in depth on the outline does the front face's
        colour now win, as a camera would see it. Front faces are set in :meth:`_state`.
        near : (n,) bool or None; for camera k with ``near[k]`` (a person may reach
            within its near plane, or enclose it) the back faces are drawn and nothing
            is clipped at the near (or far) plane: depth is clamped instead
            (``GL_DEPTH_CLAMP``), so a surface nearer than the near plane is drawn at
            depth 0, in front of the room, and a camera inside a person, which faces
            only back faces, sees that person all round, as a real lens behind someone's
            back sees them and nothing else.
        near_only : the last ``near_only`` of the ``count`` vertices (the people's soles,
            which only a camera inside a person can see) are drawn for near cameras only.
        """
        if count == 0:
            return
        near = _flags(near, len(bands))
        culling = cull and self.cull_back_faces
        if culling:
            GL.glEnable(GL.GL_CULL_FACE)
        clamped = False
        # the viewport alone does not hold a band: with depth clamping (no near-plane
        # clipping) a vertex in the lens plane made llvmpipe draw into the next band
        GL.glEnable(GL.GL_SCISSOR_TEST)
        try:
            for k, b in enumerate(bands):
                if cull and near[k] != clamped:          # toggle only where it changes
                    clamped = bool(near[k])
                    (GL.glEnable if clamped else GL.glDisable)(GL.GL_DEPTH_CLAMP)
                    if culling:
                        (GL.glDisable if clamped else GL.glEnable)(GL.GL_CULL_FACE)
                GL.glViewport(0, int(b) * self.height, self.width, self.height)
                GL.glScissor(0, int(b) * self.height, self.width, self.height)
                GL.glUniformMatrix4fv(self._u_view_proj, 1, GL.GL_TRUE, view_projs[k])
                GL.glDrawArrays(GL.GL_TRIANGLES, first, count if near[k] else count - near_only)
        finally:
            GL.glDisable(GL.GL_CULL_FACE)
            GL.glDisable(GL.GL_DEPTH_CLAMP)
            GL.glDisable(GL.GL_SCISSOR_TEST)

    def _state(self, GL, page: Page) -> None:
        """The fixed pipeline state of every pass (bound program, VAO and ``page``'s framebuffer)."""
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, page.fbo)
        GL.glUseProgram(self.program)
        GL.glBindVertexArray(self.vao)
        GL.glDisable(GL.GL_BLEND)
        GL.glDisable(GL.GL_CULL_FACE)
        GL.glDisable(GL.GL_DEPTH_CLAMP)
        GL.glFrontFace(GL.GL_CW)          # meshes wind counter-clockwise seen from outside,
        GL.glCullFace(GL.GL_BACK)         # and the projection flips rows (flip_rows)
        GL.glDisable(GL.GL_MULTISAMPLE)
        GL.glDisable(GL.GL_DITHER)
        GL.glEnable(GL.GL_DEPTH_TEST)
        GL.glDepthFunc(GL.GL_LESS)
        GL.glPolygonMode(GL.GL_FRONT_AND_BACK, GL.GL_FILL)

    def _set_offsets(self, GL, offsets_xy) -> None:
        if self.n_people:
            off = np.asarray(offsets_xy, np.float32).reshape(self.n_people, 2).copy()
            off[~np.isfinite(off).all(axis=1)] = HIDDEN
            GL.glUniform2fv(self._u_offsets, self.n_people, off)

    def store_room(self) -> None:
        """Keep a copy of every page (colour and depth) as the room.

        Call it right after a :meth:`draw` of every band with every person hidden: then
        :meth:`draw_people` can start from the room's exact colour and depth in any band.
        """
        GL = self.GL
        gl.context(self.backend)
        for page in self.pages:
            height = self.height * page.tiles
            if page.room_fbo is None:
                page.room_fbo = GL.glGenFramebuffers(1)
                GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, page.room_fbo)
                page.room_colour = GL.glGenRenderbuffers(1)
                GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, page.room_colour)
                GL.glRenderbufferStorage(GL.GL_RENDERBUFFER, GL.GL_RGBA8, self.width, height)
                GL.glFramebufferRenderbuffer(GL.GL_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, GL.GL_RENDERBUFFER,
                                             page.room_colour)
                page.room_depth = GL.glGenRenderbuffers(1)
                GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, page.room_depth)
                GL.glRenderbufferStorage(GL.GL_RENDERBUFFER, GL.GL_DEPTH_COMPONENT24, self.width, height)
                GL.glFramebufferRenderbuffer(GL.GL_FRAMEBUFFER, GL.GL_DEPTH_ATTACHMENT, GL.GL_RENDERBUFFER,
                                             page.room_depth)
                status = GL.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER)
                if status != GL.GL_FRAMEBUFFER_COMPLETE:
                    raise RuntimeError(f"OpenGL framebuffer incomplete (status 0x{int(status):x})")
            GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, page.fbo)
            GL.glBindFramebuffer(GL.GL_DRAW_FRAMEBUFFER, page.room_fbo)
            GL.glDisable(GL.GL_SCISSOR_TEST)
            GL.glBlitFramebuffer(0, 0, self.width, height, 0, 0, self.width, height,
                                 GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT, GL.GL_NEAREST)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, 0)

    def draw_people(self, view_projs: np.ndarray, offsets_xy: np.ndarray, bands, rects,
                    out: np.ndarray, near=None) -> None:
        """Draw only the people over the stored room, inside ``rects``, and read those back.

        view_projs : (n, 4, 4) float, projection @ view per camera
        offsets_xy : (n_people, 2) float, metres (NaN rows: hidden)
        bands : (n,) distinct ints in [0, n_tiles), each camera's framebuffer band (as in
            :meth:`draw`; else ValueError, before anything is drawn)
        rects : n sequences of canvas rectangles (x0, y0, x1, y1), ints, end exclusive,
            rows top first, within the canvas (else ValueError); a camera without one is skipped (nothing
            drawn, nothing read)
        out : (n_tiles, H, W, 4) uint8, C-contiguous; each of band b's rectangles is read
            into ``out[b, y0:y1, x0:x1]``, the rest of ``out`` is left alone
        near : (n,) bool, as in :meth:`draw` (default none)

        Per camera: the room's colour and depth are copied (``glBlitFramebuffer``) from
        the stored room into each rectangle, then only the people's triangles are drawn.
        Every person fragment meets exactly the depth buffer it meets in a whole-scene
        :meth:`draw` (the room's, then the people drawn before it), so inside the
        rectangles the pixels are those of the whole-scene draw, bit for bit, provided
        the rectangles hold every pixel the people cover. Requires :meth:`store_room`.
        """
        if any(page.room_fbo is None for page in self.pages):
            raise RuntimeError("draw_people: store_room() first")
        GL = self.GL
        bands = np.asarray(bands, int).reshape(-1)
        if not len(view_projs) == len(bands) == len(rects):
            raise ValueError(f"view_projs, bands, rects: expected one per camera, got "
                             f"{len(view_projs)}, {len(bands)}, {len(rects)}")
        bands = self._check_bands(bands, len(bands))
        if out.shape != self.pixels.shape or out.dtype != np.uint8 or not out.flags.c_contiguous:
            raise ValueError(f"out: expected a C-contiguous uint8 array of shape {self.pixels.shape}")
        _check_rects(rects, self.width, self.height)
        near = _flags(near, len(bands))
        todo = np.array([k for k in range(len(bands)) if len(rects[k])], int)
        if not len(todo):
            return
        gl.context(self.backend)
        vp = np.ascontiguousarray(view_projs, np.float32)
        for page, sel in self._by_page(bands[todo]):
            self._draw_people_page(GL, page, vp, offsets_xy, bands, rects, out, near, todo[sel])

    def _draw_people_page(self, GL, page: Page, vp: np.ndarray, offsets_xy, bands: np.ndarray, rects,
                          out: np.ndarray, near: np.ndarray, todo: np.ndarray) -> None:
        """:meth:`draw_people` of cameras ``todo`` (indices into the other arguments), all on ``page``."""
        H = self.height
        local = bands[todo] - page.first
        GL.glDisable(GL.GL_SCISSOR_TEST)
        GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, page.room_fbo)
        GL.glBindFramebuffer(GL.GL_DRAW_FRAMEBUFFER, page.fbo)
        for k, lb in zip(todo, local):
            b = int(lb) * H
            for x0, y0, x1, y1 in rects[k]:
                GL.glBlitFramebuffer(x0, b + y0, x1, b + y1, x0, b + y0, x1, b + y1,
                                     GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT, GL.GL_NEAREST)
        self._state(GL, page)
        self._set_offsets(GL, offsets_xy)
        self._draw_range(GL, vp[todo], local, self.people_first, self.n_vertices - self.people_first,
                         cull=True, near=near[todo], near_only=self.near_only)
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        GL.glPixelStorei(GL.GL_PACK_ROW_LENGTH, self.width)
        GL.glReadBuffer(GL.GL_COLOR_ATTACHMENT0)
        try:
            for k, lb in zip(todo, local):
                b = int(bands[k])
                for x0, y0, x1, y1 in rects[k]:
                    GL.glReadPixels(x0, int(lb) * H + y0, x1 - x0, y1 - y0, GL.GL_RGBA, GL.GL_UNSIGNED_BYTE,
                                    out[b, y0, x0:].ctypes.data)
        finally:
            GL.glPixelStorei(GL.GL_PACK_ROW_LENGTH, 0)
            GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, 0)

    def close(self) -> None:
        """Free this rasteriser's GL objects (the shared context stays)."""
        if getattr(self, "program", None) is None:
            return
        GL = self.GL
        try:
            gl.context(self.backend)
            for page in self.pages:
                GL.glDeleteFramebuffers(1, [page.fbo])
                GL.glDeleteRenderbuffers(1, [page.depth])
                GL.glDeleteTextures([page.colour])
                if page.room_fbo is not None:
                    GL.glDeleteFramebuffers(1, [page.room_fbo])
                    GL.glDeleteRenderbuffers(2, [page.room_colour, page.room_depth])
            self.pages = []
            GL.glDeleteBuffers(1, [self.vbo])
            GL.glDeleteVertexArrays(1, [self.vao])
            GL.glDeleteProgram(self.program)
        finally:
            self.program = None


def _check_rects(rects, width: int, height: int) -> None:
    """Refuse a rectangle (x0, y0, x1, y1) outside ``0 <= x0 <= x1 <= width``, ``0 <= y0 <= y1 <= height``.

    A rectangle beyond the canvas would make ``glReadPixels`` write past its slice of ``out``.
    """
    for k, cam in enumerate(rects):
        r = np.asarray(cam, dtype=np.int64).reshape(-1, 4)
        x0, y0, x1, y1 = r.T
        bad = (x0 < 0) | (y0 < 0) | (x1 < x0) | (y1 < y0) | (x1 > width) | (y1 > height)
        if bad.any():
            raise ValueError(f"rects[{k}]: rectangle {tuple(int(v) for v in r[np.argmax(bad)])} is not "
                             f"within the {width}x{height} canvas (0 <= x0 <= x1 <= {width}, "
                             f"0 <= y0 <= y1 <= {height})")


def _flags(near, n: int) -> np.ndarray:
    """``near`` as (n,) bool, all False for None."""
    near = np.zeros(n, bool) if near is None else np.asarray(near, bool).reshape(-1)
    if len(near) != n:
        raise ValueError(f"near: expected one flag per camera ({n}), got {len(near)}")
    return near


def _texture(GL, internal, width, height, fmt, dtype, data, filtering):
    tex = GL.glGenTextures(1)
    GL.glBindTexture(GL.GL_TEXTURE_2D, tex)
    GL.glPixelStorei(GL.GL_UNPACK_ALIGNMENT, 1)
    GL.glTexImage2D(GL.GL_TEXTURE_2D, 0, internal, width, height, 0, fmt, dtype, data)
    for p in (GL.GL_TEXTURE_MIN_FILTER, GL.GL_TEXTURE_MAG_FILTER):
        GL.glTexParameteri(GL.GL_TEXTURE_2D, p, filtering)
    for p in (GL.GL_TEXTURE_WRAP_S, GL.GL_TEXTURE_WRAP_T):
        GL.glTexParameteri(GL.GL_TEXTURE_2D, p, GL.GL_CLAMP_TO_EDGE)
    GL.glBindTexture(GL.GL_TEXTURE_2D, 0)
    return tex
