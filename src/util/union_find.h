/*
 * union_find.h - disjoint sets over 0..n-1 in a parent array (parent[i] = i for a root), with
 * path halving; a union makes the smaller root the root, so the representatives do not depend
 * on the order of the unions (internal: the preprocessing's part components and origin
 * clusters, contact's welded points and islands).
 */
#ifndef SEM_UTIL_UNION_FIND_H
#define SEM_UTIL_UNION_FIND_H

static inline int sem_uf_find(int *parent, int i)
{
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

static inline void sem_uf_unite(int *parent, int a, int b)
{
    a = sem_uf_find(parent, a);
    b = sem_uf_find(parent, b);
    if (a != b) parent[a > b ? a : b] = a < b ? a : b;
}

#endif
