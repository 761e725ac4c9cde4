"""Browsing with kept reference subtypes answers as asyncua's own browsing does."""

import asyncio

from asyncua import Server, ua

from app.interop.opcua import aspace_cache, browse_cache


def _descs():
    nodes = [ua.ObjectIds.ObjectsFolder, ua.ObjectIds.Server, ua.ObjectIds.TypesFolder,
             ua.ObjectIds.NonExclusiveLevelAlarmType, ua.ObjectIds.OffNormalAlarmType,
             ua.ObjectIds.ShelvedStateMachineType, ua.ObjectIds.BaseEventType,
             ua.ObjectIds.References]
    refs = [ua.ObjectIds.Null, ua.ObjectIds.HierarchicalReferences, ua.ObjectIds.HasChild,
            ua.ObjectIds.HasComponent, ua.ObjectIds.HasSubtype, ua.ObjectIds.References,
            ua.ObjectIds.NonHierarchicalReferences]
    for n in nodes:
        for r in refs:
            for sub in (True, False):
                for direction in (ua.BrowseDirection.Forward, ua.BrowseDirection.Both):
                    d = ua.BrowseDescription()
                    d.NodeId, d.ReferenceTypeId = ua.NodeId(n), ua.NodeId(r)
                    d.IncludeSubtypes, d.BrowseDirection = sub, direction
                    d.ResultMask = ua.BrowseResultMask.All
                    yield d


def _refs(view, descs):
    p = ua.BrowseParameters()
    p.NodesToBrowse = descs
    return [[(r.NodeId, r.ReferenceTypeId, r.IsForward) for r in res.References]
            for res in view.browse(p)]


def test_cached_browse_answers_as_asyncua_does():
    async def main():
        server, _ = await aspace_cache.initialised(Server)  # the run's cached standard nodes
        view = server.iserver.view_service
        descs = list(_descs())
        plain = _refs(view, descs)
        assert browse_cache.install(server)
        cached = _refs(view, descs)
        assert view._subtype_sets  # the kept sets were used
        assert ua.NodeId(ua.ObjectIds.HasComponent) in \
            view._subtype_sets[ua.NodeId(ua.ObjectIds.HierarchicalReferences)]
        browse_cache.forget(server)
        assert not view._subtype_sets
        return plain, cached

    plain, cached = asyncio.run(main())
    assert cached == plain
    assert sum(map(len, plain)) > 100 and any(not r for r in plain)  # both kinds were asked


def test_install_refuses_a_server_it_does_not_know():
    class Odd:
        iserver = object()

    assert browse_cache.install(Odd()) is False
