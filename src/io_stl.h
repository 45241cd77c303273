/* STL triangle meshes, ASCII and binary (docs/meshes.md): read whole, checked, and handed over
 * as triangles in the file's own units. Nothing here knows the world: the scenario transforms
 * the triangles and the builder adds them as walls. */
#ifndef SD_IO_STL_H
#define SD_IO_STL_H

#include <stddef.h>

#include "sabodem.h"

/* Files larger than this are refused before anything is read (a binary STL of a million
 * triangles takes 50 MB; the same in ASCII ~250 MB). */
#define SD_STL_MAX_BYTES (256.0 * 1024 * 1024)
/* The most triangles of one file, and of all of a scenario's meshes together. */
#define SD_STL_MAX_TRIANGLES 1000000

typedef struct {
    sd_vec3 (*tri)[3]; /* the triangles' corners, in file order, in the file's units */
    int *where;        /* each triangle's place: the line of its 'facet' (ASCII), its index (binary) */
    int n;
    int binary; /* 1: read as binary, 0: as ASCII */
    /* zero-area triangles are dropped, not refused: how many, and where the first was */
    int dropped;
    int first_dropped;
} sd_stl_mesh;

/* Read the STL file at path (a regular file of at most SD_STL_MAX_BYTES) into m, at most
 * max_triangles of them. 0 on success; -1 with the reason in msg, which names the file and the
 * line (ASCII) or the byte offset and the triangle (binary), and m left empty. */
int sd_stl_read(const char *path, int max_triangles, sd_stl_mesh *m, char *msg, size_t msglen);
/* The same from len bytes in memory; name stands for the file in the messages. */
int sd_stl_parse(const void *data, size_t len, const char *name, int max_triangles, sd_stl_mesh *m, char *msg,
                 size_t msglen);
void sd_stl_free(sd_stl_mesh *m);
/* "line 12" or "triangle 3 (byte offset 234)": where triangle k of m came from, into buf */
const char *sd_stl_where(const sd_stl_mesh *m, int k, char *buf, size_t len);

#endif
